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
special angle; :func:`angle_rounding` gives the largest such rounding, and the rank tolerance of
:mod:`excite_cli.dynamics.base_parameters` is ``ROUNDING_FACTOR`` times it. Files written to full
precision (``1.57079632679``, example-robot-data's Panda, UR, G1) round by ≤ 5e-12 and keep the
float tolerance.
"""

from __future__ import annotations

import math
from decimal import Decimal, InvalidOperation
from pathlib import Path
from xml.etree import ElementTree

#: Special angles: multiples of this [rad] (15°: right angles, and 30°, 45°, 60° mounts).
SPECIAL_ANGLE = math.pi / 12
#: Coarsest rounding read as a rounded special angle: half a unit of the 2nd decimal [rad].
COARSEST = 5e-3
#: The rank tolerance is this many times the largest rounding: spurious directions measured at
#: 0.3–1.0 times it (so101, a 7-axis arm and a 3-joint arm with π/2 written 1.5708).
ROUNDING_FACTOR = 10.0


def _rounding(text: str) -> float:
    """How far the angle ``text`` [rad] is from the multiple of π/12 it rounds, 0 when it rounds none."""
    try:
        written = Decimal(text)
    except InvalidOperation:
        return 0.0
    if not written.is_finite():
        return 0.0
    half_unit = 0.5 * 10.0 ** written.as_tuple().exponent
    value = float(written)
    distance = abs(value - round(value / SPECIAL_ANGLE) * SPECIAL_ANGLE)
    return distance if distance <= min(half_unit, COARSEST) else 0.0


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
