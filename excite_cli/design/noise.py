"""The torque noise a design is for: heteroscedastic weights of the regressor rows.

A lab's torque reading has noise of variance σ_j² + ρ_j² τ_j(t)² at joint j and instant t: an
absolute part σ_j [Nm] (a torque sensor's) and a part ρ_j [1] growing with the torque (a motor
current's model: gear friction and torque-constant errors scale with the load). Weighted least
squares weighs each row by the inverse noise, so the information the measurements will deliver is
CᵀW²C with the rows of C scaled by

    s_{t,j} = σ̄ / √(σ_j² + ρ_j² τ_j(t)²)

(Gautier 1997 with a noise that depends on the sample; σ̄, the geometric mean of the σ_j, keeps the
criterion on the scale of the unweighted rows: equal noise on every joint and ρ = 0 weigh each row
1). τ is the rigid body's inverse dynamics with the URDF's inertias at the trajectory's motion, so
the weights move with α and their gradient ∂s/∂τ = −s ρ² τ / (σ² + ρ²τ²) enters the criterion's
(:mod:`~excite_cli.design.criterion`). The rows of the base wrench (a floating base's, which
no joint's sensor measures) weigh as a row of noise σ̄.

With an identify report as prior data (``sequence.prior``), the new trajectory's rows are weighed by
the noise the report fitted, a_j and ρ_j (:mod:`~excite_cli.identification.fitting.noise_level`), as
the rows of its recording are (:class:`~excite_cli.stored.design_model.MeasuredPrior`), or by the
report's σ_j and the config's ρ where the report has no fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from excite_cli.config import NoiseConfig
from excite_cli.constraints.joint_limits import per_joint
from excite_cli.dynamics.robot import Robot
from excite_cli.stored.design_model import MeasuredPrior

#: Random feasible motions (the seeds of :meth:`~excite_cli.design.excitation.Excitation.random_start`)
#: whose RMS torques are a joint's typical torque (:func:`typical_torques`).
TYPICAL_SEEDS = (1, 2, 3)
#: K [1]: where the lab declares no noise, the design assumes noise √((K R_j)² + τ_j(t)²) (up to
#: scale): growing with the torque over a floor of K times the joint's typical torque R_j. Chosen by
#: the smallest worst regret over absolute and relative truths on four robots (the figures page,
#: "Which noise the design assumes when the lab declares none").
HEDGE_FLOOR = 0.5
#: What a design for the hedge says it weighs its rows by.
HEDGE_WORDS = (
    f"the noise assumed where none is declared: growing with the torque over a floor of {HEDGE_FLOOR:g} × each "
    "joint's typical torque (declare `noise:`, or design from an identify report, which measures it)"
)


@dataclass(frozen=True)
class RowNoise:
    """The noise of each regressor row of one instant.

    Attributes:
        sigma: (n_rows,) the absolute part σ [Nm] of each row's noise.
        rho: (n_rows,) the part ρ [1] relative to the row's torque (0 on the base wrench rows).
        scale: σ̄ [Nm], the geometric mean of the joints' σ_j: a row of noise σ̄ weighs 1.
        reference: (p,) the standard parameters φ [kg, kg·m, kg·m²] the torques are computed with
            (the URDF's).
        source: where the noise comes from, in words.
    """

    sigma: np.ndarray
    rho: np.ndarray
    scale: float
    reference: np.ndarray
    source: str = "the config's noise section"

    @property
    def words(self) -> str:
        """What the rows are weighed by, in words (``source``)."""
        return f"the rows weighed by {self.source}"

    @property
    def varying(self) -> bool:
        """Whether the weights depend on the torque (some ρ > 0)."""
        return bool(np.any(self.rho > 0.0))

    def weights(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """s (M,) = σ̄ / √(σ² + ρ² τ²) of M = T·n_rows rows whose torques are ``tau`` (M,) [Nm],
        instants one after the other, and ds/dτ (M,) [1/Nm]."""
        reps = tau.size // self.sigma.size
        sigma, rho = np.tile(self.sigma, reps), np.tile(self.rho, reps)
        variance = sigma**2 + rho**2 * tau**2
        s = self.scale / np.sqrt(variance)
        return s, -s * rho**2 * tau / variance


def hedged_noise(joints: list[str], typical: np.ndarray) -> NoiseConfig:
    """The noise a design assumes where the lab declares none: σ_j = :data:`HEDGE_FLOOR` R_j and ρ = 1,
    σ_j(t)² = (K R_j)² + τ_j(t)² (only the ratios between rows change a design).

    Args:
        joints: (n,) the active joints.
        typical: R_j (n,) [Nm], their typical torques (:func:`typical_torques`).
    """
    return NoiseConfig(absolute={j: HEDGE_FLOOR * float(r) for j, r in zip(joints, typical)}, relative=1.0)


def row_noise(
    cfg: NoiseConfig | None, robot: Robot, measured: MeasuredPrior | None, hedged: bool = False
) -> RowNoise | None:
    """The rows' noise of the ``noise`` section, or of ``measured`` (an identify report's) when there
    is one: its fitted a_j and ρ_j (:meth:`~excite_cli.stored.design_model.MeasuredPrior.noise_parts`; a
    floor keeps a row of zero torque finite) or, without them, its σ_j
    and the config's ρ. None where there is no section and no measured prior (the paper's cond, or a
    robot without inertias: :func:`~excite_cli.design.resolve.resolve` gives every other design the
    hedge of :func:`hedged_noise` as its section).
    ``hedged``: the section is the hedge of :func:`hedged_noise`, not the config's (the words say so).

    Raises:
        ExciteError: (``noise.absolute``, ``noise.relative``) an unknown joint, a σ that is not positive
            and finite, a ρ that is negative or not finite.
    """
    if cfg is None and measured is None:
        return None
    n, rows = robot.n_joints, robot.n_rows
    if measured is not None:
        order = [measured.joints.index(j) for j in robot.joint_names]
        sigma = measured.floored[order]
    else:
        sigma = per_joint("noise.absolute", cfg.absolute, np.full(n, np.nan), robot, noun="noise [Nm]")
    rho = np.zeros(n) if cfg is None else per_joint("noise.relative", cfg.relative, np.zeros(n), robot, True, "noise")
    source = HEDGE_WORDS if hedged else "the config's noise section"
    if measured is not None and measured.level is not None:
        sigma, rho = (x[order] for x in measured.noise_parts())
        source = "the noise the identify report measured (sequence.prior): " + ", ".join(
            f"{j} {a:.3g} Nm + {100 * r:.3g} % of τ" for j, a, r in zip(robot.joint_names, sigma, rho)
        )
    elif measured is not None:
        source = "the identify report's validation error per joint (sequence.prior)" + (
            " and the config's noise.relative" if np.any(rho > 0) else ""
        )
    if measured is not None:
        scale = measured.noise
    else:  # σ̄, the geometric mean; exactly σ where every joint's is the same, so those rows weigh exactly 1
        scale = float(sigma[0]) if np.all(sigma == sigma[0]) else float(np.exp(np.log(sigma).mean()))
    return RowNoise(
        sigma=np.concatenate([np.full(rows - n, scale), sigma]),
        rho=np.concatenate([np.zeros(rows - n), rho]),
        scale=scale,
        reference=robot.urdf_parameters(),
        source=source,
    )


def typical_torques(excitation) -> np.ndarray:
    """R_j (n,) [Nm]: each active joint's RMS torque (the URDF's rigid body, RNEA) over the random
    feasible motions :data:`TYPICAL_SEEDS` of ``excitation`` (an
    :class:`~excite_cli.design.excitation.Excitation`), at its cost samples; a joint whose torque stays
    below 1e-6 of the largest is given that (a noise floor must be positive)."""
    robot, n = excitation.robot, excitation.robot.n_joints
    tau = [
        robot.torques(*x)[-n:]  # the joints' rows (a floating base's 6 wrench rows come first)
        for seed in TYPICAL_SEEDS
        for x in zip(*excitation.cost_basis.evaluate(excitation.random_start(np.random.default_rng(seed))))
    ]
    rms = np.sqrt(np.mean(np.square(tau), axis=0))
    return np.maximum(rms, 1e-6 * rms.max())
