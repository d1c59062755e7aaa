"""The right angles a URDF writes rounded, and the rank tolerance they call for.

Vendors write π/2 as ``1.5708`` (3.7e-6 rad off) or π as ``3.14``: the joint axes the rounding
tilts are then not exactly parallel or perpendicular, and regroupings that hold for the real robot
(Khalil and Dombre, "Modeling, Identification and Control of Robots", 2002, §12.5: parallel and
perpendicular axes) fail by that much. The regressor gains directions whose size is the rounding
(pivots of 1e-6 of the largest on example-robot-data's so101, which writes ``1.5708`` and
``3.14159``), which no motion can excite above the torque noise: counted as base parameters they
would dominate cond(C) and come out of an identification as 0.06 ± 8.

Read here: each ``rpy`` angle of a joint's origin that is a multiple of π/12 (15°) to the file's
last written digit (within half a unit of it, and written to at least 2 decimals) is a rounded
special angle, where its digits are evidence of one: a real angle would write them by chance (one
written unit over the spacing of the coarsest family of special angles it rounds: π/2, π/4, π/6 or
π/12) at most :data:`CHANCE` of the time. ``1.5708``, ``3.14`` and ``0.785`` are rounded π/2, π and
π/4; ``0.26`` is not a rounded 15° (a real 14.9° mount writes it, 4 % of angles would) nor ``-0.79``
a rounded −π/4 (1.3 %). :func:`angle_rounding` gives the largest such rounding, and the rank tolerance of
:mod:`excite_cli.dynamics.base_parameters` is ``ROUNDING_FACTOR`` times it. Files written to full
precision (``1.57079632679``, example-robot-data's Panda, UR, G1) round by ≤ 5e-12 and keep the
float tolerance.
"""

from __future__ import annotations

import math
from decimal import Decimal, InvalidOperation
from pathlib import Path
from xml.etree import ElementTree

#: Special angles: multiples of these [rad], coarsest first (right angles, and 45°, 30°, 15° mounts).
SPECIAL_ANGLES = (math.pi / 2, math.pi / 4, math.pi / 6, math.pi / 12)
#: The most often a real angle may write a special angle's digits for them to be read as its rounding.
CHANCE = 0.01
#: Coarsest rounding read as a rounded special angle: half a unit of the 2nd decimal [rad].
COARSEST = 5e-3
#: The rank tolerance is this many times the largest rounding: spurious directions measured at
#: 0.3–1.0 times it (so101, a 7-axis arm and a 3-joint arm with π/2 written 1.5708).
ROUNDING_FACTOR = 10.0


def _rounding(text: str) -> float:
    """How far the angle ``text`` [rad] is from the special angle it rounds (module docstring), 0 when
    it rounds none or its digits are no evidence of one."""
    try:
        written = Decimal(text)
    except InvalidOperation:
        return 0.0
    if not written.is_finite():
        return 0.0
    unit = 10.0 ** written.as_tuple().exponent
    value = float(written)
    for spacing in SPECIAL_ANGLES:
        distance = abs(value - round(value / spacing) * spacing)
        if distance <= min(0.5 * unit, COARSEST):
            return distance if unit / spacing <= CHANCE else 0.0
    return 0.0


def angle_rounding(path: Path) -> float:
    """Largest rounding [rad] of a special angle in the ``rpy`` of the URDF's joint origins (module
    docstring); 0 for a file written to full precision, or one that is not XML (checked elsewhere)."""
    try:
        root = ElementTree.parse(path).getroot()
    except (ElementTree.ParseError, OSError):
        return 0.0
    origins = (joint.find("origin") for joint in root.iter("joint"))
    angles = [text for origin in origins if origin is not None for text in (origin.get("rpy") or "").split()]
    return max((_rounding(text) for text in angles), default=0.0)
