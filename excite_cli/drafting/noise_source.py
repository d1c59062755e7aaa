"""The ``noise:`` section ``excite init`` drafts from where the lab's joint torques come from
(``--torque-from``): the design weighs each regressor row by the noise it expects
(:mod:`~excite_cli.design.noise`), and the kind of noise decides the best design (a design for
absolute noise loses 41-61 % under noise growing with the torque, and the reverse 31-310 %: the
figures page, "Which noise the design assumes").

- ``sensor`` (a joint torque sensor): absolute noise, :data:`SENSOR_FLOOR` of each joint's typical
  torque R_j (its RMS torque on random feasible motions, :func:`~excite_cli.design.noise.typical_torques`:
  a sensor's range, and so its noise, follows the torque the joint is built for).
- ``current`` (the torque estimated from motor current): :data:`RELATIVE` of the torque (torque-constant
  and gear errors scale with the load) over a floor of :data:`CURRENT_FLOOR` of R_j (the current
  reading's own noise).
- ``unknown``: no section: the design's default, the hedge for undeclared noise
  (:func:`~excite_cli.design.noise.hedged_noise`, chosen on the figures page, "Which noise the design
  assumes when the lab declares none"), and the comment says how to declare the source.

Only the ratios between the rows' noises change a design; the σ [Nm] written are a guess to replace
with the lab's figures, or with an identify report's (``sequence.prior``).
"""

from __future__ import annotations

import numpy as np

#: ``--torque-from`` values.
SOURCES = ("sensor", "current", "unknown")
#: ρ [1]: the part of the noise that grows with the torque (current, unknown).
RELATIVE = 0.02
#: σ_j as a fraction of the joint's typical torque R_j: a sensor's, and a current reading's floor.
SENSOR_FLOOR, CURRENT_FLOOR = 0.02, 0.002


def draft_noise(source: str, joints: list[str], typical: np.ndarray) -> tuple[dict | None, str]:
    """The drafted ``noise`` section (None: none) and the sentence saying what it assumes.

    Args:
        source: where the torque comes from, one of :data:`SOURCES`.
        joints: (n,) the active joints.
        typical: R_j (n,) [Nm], their typical torques (:func:`~excite_cli.design.noise.typical_torques`).
    """
    typical_words = "each joint's RMS torque on random feasible motions"
    if source == "unknown":
        return None, (
            "none: the torque source was not said, so the design hedges between a sensor's noise and a motor "
            "current's (noise growing with the torque over a floor of half each joint's typical torque; init's "
            "torque_from sensor or current drafts the noise of either; an identify report as sequence.prior "
            "measures it)"
        )
    floor = SENSOR_FLOOR if source == "sensor" else CURRENT_FLOOR
    sigma = {j: float(f"{floor * r:.3g}") for j, r in zip(joints, typical)}
    if source == "sensor":
        return {"absolute": sigma}, (
            f"torque from joint torque sensors: absolute noise, {SENSOR_FLOOR:.0%} of {typical_words}; "
            "replace with your sensors' figures"
        )
    return {"absolute": sigma, "relative": RELATIVE}, (
        f"torque from motor current: {RELATIVE:.0%} of the torque over a floor of {CURRENT_FLOOR:.1%} of "
        f"{typical_words}; replace with your figures, or design the next run from an identify report "
        "(sequence.prior), which measures them"
    )
