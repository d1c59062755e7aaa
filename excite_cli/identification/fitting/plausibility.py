"""Measured torques a fit should not be trusted with, said before anyone reads its numbers: a joint
whose torque runs against the URDF model's (a flipped sign) or is several times larger or smaller
than it (another unit), and least-squares bodies with a negative mass, each named with its likely
cause and the config field to look at.

The URDF's inertias are rough (CAD, often tens of percent off) but not off by a sign or a factor of
five: where the URDF model explains a joint's torque at all (|cos| ≥ :data:`AGREEMENT` between the
measured and the modelled torque, as gravity does on every joint that carries a load), its slope
(the least-squares factor from model to measurement) is near 1."""

from __future__ import annotations

from typing import Optional

import numpy as np

from excite_cli.dynamics.robot import Robot
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.physical import ConsistentFit

#: |cos| between measured and URDF-modelled torques above which the URDF model explains a joint.
AGREEMENT = 0.7
#: A slope outside [1/SCALE, SCALE] is another unit rather than a rough URDF.
SCALE = 5.0


def urdf_disagreements(data: Dataset, urdf_base: np.ndarray, joints: list[str]) -> list[str]:
    """The joints whose measured torque disagrees with the URDF model's, in words.

    Args:
        data: the fit data (regressor rows (N·n, b), torques (N·n,) [Nm]).
        urdf_base: (b,) the URDF's base parameters (``K φ_URDF``, Eq. 3).
        joints: (n,) the joints' names.

    Returns:
        One line per joint whose torque runs against the model (cos ≤ −:data:`AGREEMENT`: a flipped
        sign, ``data.signs`` or ``data.torque_constants``) or follows it with a slope outside
        [1/:data:`SCALE`, :data:`SCALE`] (another unit, ``data.columns.factors``).
    """
    model = (data.regressor @ urdf_base).reshape(-1, data.n)
    measured = data.tau.reshape(-1, data.n)
    lines = []
    for j, name in enumerate(joints):
        p, t = model[:, j], measured[:, j]
        norms = np.linalg.norm(p) * np.linalg.norm(t)
        if norms == 0.0:
            continue
        cosine, slope = float(p @ t) / norms, float(p @ t) / float(p @ p)
        if cosine <= -AGREEMENT:
            lines.append(
                f"{name}: the measured torque runs against the URDF model's (slope {slope:.2f}): "
                "a flipped sign? (data.signs, data.torque_constants)"
            )
        elif cosine >= AGREEMENT and not 1.0 / SCALE <= slope <= SCALE:
            lines.append(
                f"{name}: the measured torque is {slope:.3g} times the URDF model's: another unit? "
                "(data.columns.factors, data.torque_constants)"
            )
    return lines


def negative_masses(standard: np.ndarray, bodies: list[str], disagreements: list[str]) -> list[str]:
    """The bodies a least-squares fit gives a negative mass, in words, with the likely cause.

    Args:
        standard: (10·bodies,) standard parameters of the fit (m, m·c, I per body; pinocchio's order).
        bodies: the bodies' names.
        disagreements: :func:`urdf_disagreements`' lines (a sign or unit is then the likely cause).

    Returns:
        One line naming the bodies and their masses [kg], or none.
    """
    negative = [f"{name} ({standard[10 * i]:.3g} kg)" for i, name in enumerate(bodies) if standard[10 * i] < 0.0]
    if not negative:
        return []
    cause = (
        "the torque signs or units named above"
        if disagreements
        else "too little excitation of the joints that move them, or torques that are not the joints' own"
    )
    return [f"least squares gives negative masses to {', '.join(negative)}: likely {cause}"]


def implausible(data: Dataset, urdf_base: np.ndarray, robot: Robot, consistent: Optional[ConsistentFit]) -> list[str]:
    """:func:`urdf_disagreements` and, with a consistent fit beside it, the plain least squares'
    :func:`negative_masses` (its ``unconstrained`` standard parameters), as report warnings."""
    lines = urdf_disagreements(data, urdf_base, robot.joint_names)
    if consistent is not None:
        lines += negative_masses(consistent.unconstrained, robot.body_names, lines)
    return lines
