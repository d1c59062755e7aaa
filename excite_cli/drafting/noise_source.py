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
- ``unknown``: the hedged model, :data:`RELATIVE` of the torque over a floor of :data:`HEDGE_FLOOR` of
  R_j: the design that loses least under either kind (measured on four robots).

Only the ratios between the rows' noises change a design; the σ [Nm] written are a guess to replace
with the lab's figures, or with an identify report's (``sequence.prior``).
"""

from __future__ import annotations

import numpy as np

#: ``--torque-from`` values.
SOURCES = ("sensor", "current", "unknown")
#: ρ [1]: the part of the noise that grows with the torque (current, unknown).
RELATIVE = 0.02
#: σ_j as a fraction of the joint's typical torque R_j: a sensor's, a current reading's floor, the hedge's floor.
SENSOR_FLOOR, CURRENT_FLOOR, HEDGE_FLOOR = 0.02, 0.002, 0.02


def draft_noise(source: str, joints: list[str], typical: np.ndarray) -> tuple[dict, str]:
    """The drafted ``noise`` section and the sentence saying what it assumes.

    Args:
        source: where the torque comes from, one of :data:`SOURCES`.
        joints: (n,) the active joints.
        typical: R_j (n,) [Nm], their typical torques (:func:`~excite_cli.design.noise.typical_torques`).
    """
    floor = {"sensor": SENSOR_FLOOR, "current": CURRENT_FLOOR, "unknown": HEDGE_FLOOR}[source]
    sigma = {j: float(f"{floor * r:.3g}") for j, r in zip(joints, typical)}
    typical_words = "each joint's RMS torque on random feasible motions"
    if source == "sensor":
        return {"absolute": sigma}, (
            f"torque from joint torque sensors: absolute noise, {SENSOR_FLOOR:.0%} of "
            f"{typical_words}; replace with your sensors' figures"
        )
    section = {"absolute": sigma, "relative": RELATIVE}
    if source == "current":
        return section, (
            f"torque from motor current: {RELATIVE:.0%} of the torque over a floor of "
            f"{CURRENT_FLOOR:.1%} of {typical_words}; replace with your figures, or design the next run from an "
            "identify report (sequence.prior), which measures them"
        )
    return section, (
        f"torque source not said (sensor or current): the hedge, {RELATIVE:.0%} of the torque "
        f"over a floor of {HEDGE_FLOOR:.0%} of {typical_words}, the design that loses least under either "
        "kind; an identify report (sequence.prior) measures the noise for the next run"
    )
