"""How far a restart's end point is from a local optimum, and why its solver stopped.

First-order optimality (Karush-Kuhn-Tucker) of min f(z) s.t. g(z) ≤ 0 at z: the constraints within
``ACTIVE_TOLERANCE`` of their bound are active, their multipliers λ ≥ 0 are the non-negative least
squares solution of ∇f + J_Aᵀλ = 0, and the residual is

    r = max(‖∇f + J_Aᵀλ‖_∞, max_i λ_i |g_i|) / max(1, ‖∇f‖_∞)

(stationarity and complementarity, scaled as IPOPT scales its dual infeasibility). r = 0 at a KKT
point. z are the optimizer's preconditioned variables (:mod:`excite_cli.trajectory.boundary`), so the
residual does not depend on the units of the Fourier coefficients.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.optimize import nnls

from excite_cli.constraints.lse import GRID_MARGIN

#: A constraint counts as active when g ≥ −this (normalized units: the aggregation's own margin).
ACTIVE_TOLERANCE = GRID_MARGIN
#: The iterations over which "still improving" is judged (at least, or a tenth of the run).
IMPROVEMENT_WINDOW = 10
#: A decrease of the objective over that window larger than this (relative to max(1, |f|)) is progress.
IMPROVEMENT = 1e-3

#: The stop reasons a restart can end with (``INFEASIBLE``: no end point met a constraint that needs
#: motion; ``TIME_BUDGET``: ``optimizer.time_budget`` ran out first, a result that depends on the machine).
CONVERGED, STILL_IMPROVING, STALLED, SOLVER_FAILED, INFEASIBLE, TIME_BUDGET = (
    "converged",
    "iteration limit, still improving",
    "stalled",
    "solver failed",
    "infeasible",
    "time budget",
)


@dataclass(frozen=True)
class Optimality:
    """First-order optimality at a point.

    Attributes:
        residual: the scaled KKT residual r (dimensionless, 0 at a KKT point).
        active: number of active constraints.
        gradient_norm: ‖∇f‖_∞ in the optimizer's variables.
        max_constraint: max_i g_i (normalized, ≤ 0 inside).
    """

    residual: float
    active: int
    gradient_norm: float
    max_constraint: float


def kkt_optimality(gradient: np.ndarray, values: np.ndarray, jacobian: np.ndarray) -> Optimality:
    """The KKT residual (module docstring) from ∇f (n_z,), g (m,) and ∂g/∂z (m, n_z) at one point."""
    active = values >= -ACTIVE_TOLERANCE
    lam = (
        nnls(jacobian[active].T, -gradient, maxiter=50 * max(1, int(active.sum())))[0] if active.any() else np.zeros(0)
    )
    stationarity = np.abs(gradient + jacobian[active].T @ lam).max() if gradient.size else 0.0
    complementarity = float(np.max(lam * np.abs(values[active]), initial=0.0))
    norm = float(np.abs(gradient).max(initial=0.0))
    return Optimality(
        max(stationarity, complementarity) / max(1.0, norm), int(active.sum()), norm, float(values.max(initial=-np.inf))
    )


def stop_reason(
    optimality: Optimality,
    history: Sequence[float],
    limit: bool,
    failed: bool,
    tolerance: float,
    out_of_time: bool = False,
) -> str:
    """Why a restart ended, honestly: ``converged`` when its end point meets the KKT ``tolerance``
    (whatever the solver said); else ``solver failed`` (line search or subproblem), ``time budget``
    (``out_of_time``: the iteration's wall-time budget stopped it), ``iteration limit, still
    improving`` (the objective ``history`` (one value per iteration) still fell by more than
    ``IMPROVEMENT`` over its last ``IMPROVEMENT_WINDOW`` iterations or tenth), or ``stalled``."""
    if optimality.residual <= tolerance:
        return CONVERGED
    if failed:
        return SOLVER_FAILED
    if out_of_time:
        return TIME_BUDGET
    window = max(IMPROVEMENT_WINDOW, len(history) // 10)
    if limit and len(history) > window:
        before, recent = history[-window - 1], min(history[-window:])
        if before - recent > IMPROVEMENT * max(1.0, abs(before)):
            return STILL_IMPROVING
    return STALLED
