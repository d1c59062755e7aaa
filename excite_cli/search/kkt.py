"""How far a restart's end point is from a local optimum, and why its solver stopped.

First-order optimality (Karush-Kuhn-Tucker) of min f(z) s.t. g(z) ≤ 0 at z: the constraints within
``ACTIVE_TOLERANCE`` of their bound are active, their multipliers λ ≥ 0 are the non-negative least
squares solution of ∇f + J_Aᵀλ = 0, and the residual is

    r = max(‖∇f + J_Aᵀλ‖_∞, max_i λ_i |g_i|) / max(1, ‖∇f‖_∞)

(stationarity and complementarity, scaled as IPOPT scales its dual infeasibility). r = 0 at a KKT
point. z are the optimizer's preconditioned variables (:mod:`excite_cli.trajectory.boundary`), so the
residual does not depend on the units of the Fourier coefficients.

The condition number and E-optimality are functions of the extreme singular values, and not
differentiable where an extreme one is multiple; an optimum of cond is typically such a point (the
optimizer evens out the largest and the smallest singular values until several are equal: 8 and 2
within 10⁻⁵ at a stalled G1 end point), where the gradient of any one eigenbasis, all a solver
sees, does not vanish and r stays large (0.49 there). The measure there is Clarke's (Clarke 1983):
the singular values within ``CLUSTER`` of an extreme form its cluster, whose subdifferential of
log σ is {Σ_ab S_ab ∇h_ab : S ⪰ 0, tr S = 1} (the derivative of a multiple eigenvalue, Overton 1992;
h_ab from :meth:`~excite_cli.design.criterion.Criterion.cluster_gradients`), and

    r = min over S_c ⪰ 0 with tr S_c = 1, ν ≥ 0 of
        max(‖Σ_c w_c Σ_ab S_c,ab ∇h_c,ab + J_Aᵀν‖_∞, max_i ν_i |g_i|) / max(1, ‖∇f‖_∞)

(w_c the criterion's weight on that extreme, times f for cond itself): a semidefinite program,
solved by Clarabel through cvxpy, 0 at a Clarke-stationary point; with single extremes it is r
above. At that G1 point it is 1.5e-3 (the individual singular values' gradients alone, S diagonal:
0.021).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from enum import StrEnum
from typing import Callable, Protocol, Sequence

import numpy as np
from scipy.optimize import nnls

from excite_cli.constraints.lse import GRID_MARGIN

#: A constraint counts as active when g ≥ −this (normalized units: the aggregation's own margin).
ACTIVE_TOLERANCE = GRID_MARGIN
#: Singular values within this relative distance of an extreme one form its cluster (the Clarke test).
CLUSTER = 0.01
#: At most this many singular values per cluster (k(k+1) passes of RNEA derivatives).
CLUSTER_SIZE = 10
#: The iterations over which "still improving" is judged (at least, or a tenth of the run).
IMPROVEMENT_WINDOW = 10
#: A decrease of the objective over that window larger than this (relative to max(1, |f|)) is progress.
IMPROVEMENT = 1e-3
#: The solver's iterates between two Clarke tests of a non-smooth criterion (each a small SDP).
NONSMOOTH_EVERY = 10


class Stop(StrEnum):
    """The stop reasons a restart can end with (``INFEASIBLE``: no end point met a constraint that needs
    motion; ``TIME_BUDGET``: ``optimizer.time_budget`` ran out first, a result that depends on the
    machine; ``SCREENED_OUT``: left after its first solver iterations for better starts). Members are
    the words results store and tables print."""

    CONVERGED = "converged"
    STILL_IMPROVING = "iteration limit, still improving"
    STALLED = "stalled"
    SOLVER_FAILED = "solver failed"
    INFEASIBLE = "infeasible"
    TIME_BUDGET = "time budget"
    SCREENED_OUT = "screened out"


CONVERGED, STILL_IMPROVING, STALLED, SOLVER_FAILED, INFEASIBLE, TIME_BUDGET, SCREENED_OUT = Stop


class End(StrEnum):
    """Which point a restart kept (:class:`~excite_cli.search.optimizer.RestartResult`): its start, the
    feasible point nearest the solver's last iterate (``PROJECTED``), a point towards the start
    (``BISECTION``: never kept as the solver's own), its best iterate inside every constraint
    (``INSIDE``), an earlier iteration's optimum it started from and did not leave (``EARLIER``:
    :mod:`~excite_cli.search.earlier_optimum`), or none (no end point met a constraint that needs motion)."""

    START = "start"
    EARLIER = "earlier optimum"
    PROJECTED = "projected"
    BISECTION = "bisection"
    INSIDE = "inside"
    NONE = "none"


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


def extreme_clusters(sigma: np.ndarray, extremes: tuple[float, ...]) -> list[tuple[np.ndarray, float]]:
    """(indices into ``sigma`` (b,) ascending, weight) of each extreme a criterion weighs (``extremes``
    = (w_max, w_min), a zero weight left out): the singular values within ``CLUSTER`` of it, at most
    ``CLUSTER_SIZE``, nearest first."""
    out = []
    if extremes and extremes[0]:
        top = np.flatnonzero(sigma >= sigma[-1] * (1.0 - CLUSTER))[::-1][:CLUSTER_SIZE]
        out.append((top, extremes[0]))
    if extremes and extremes[1]:
        bottom = np.flatnonzero(sigma <= sigma[0] * (1.0 + CLUSTER))[:CLUSTER_SIZE]
        out.append((bottom, extremes[1]))
    return out


def clarke_optimality(
    clusters: Sequence[np.ndarray], gradient: np.ndarray, values: np.ndarray, jacobian: np.ndarray
) -> Optimality:
    """The Clarke residual (module docstring) from each cluster's weighted gradients ∇h_ab in z
    (k_c, k_c, n_z), ∇f (n_z,) (the solver's, for the scale), g (m,) and ∂g/∂z (m, n_z) at one point."""
    import cvxpy as cp  # here: the command line starts without it

    active = values >= -ACTIVE_TOLERANCE
    weights = [cp.Variable((len(c), len(c)), PSD=True) for c in clusters]
    nu = cp.Variable(int(active.sum()), nonneg=True)
    combination = jacobian[active].T @ nu
    for S, c in zip(weights, clusters):
        combination = combination + c.reshape(len(c) ** 2, -1).T @ cp.vec(S, order="C")
    problem = cp.Problem(cp.Minimize(cp.norm(combination, "inf")), [cp.trace(S) == 1 for S in weights])
    try:
        with warnings.catch_warnings():  # an inaccurate solution is judged by its status below, not printed
            warnings.simplefilter("ignore", UserWarning)
            problem.solve(solver=cp.CLARABEL)
    except cp.error.SolverError:
        return kkt_optimality(gradient, values, jacobian)
    if problem.status != cp.OPTIMAL:  # an inaccurate certificate certifies nothing: the smooth test
        return kkt_optimality(gradient, values, jacobian)
    multipliers = np.maximum(nu.value, 0.0) if active.any() else np.zeros(0)
    complementarity = float(np.max(multipliers * np.abs(values[active]), initial=0.0))
    norm = float(np.abs(gradient).max(initial=0.0))
    residual = max(float(problem.value), complementarity) / max(1.0, norm)
    return Optimality(residual, int(active.sum()), norm, float(values.max(initial=-np.inf)))


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


class Stationarity(Protocol):
    """What the stopping test asks of a problem (:class:`~excite_cli.search.nlp.Evaluations`): its
    stacked constraint values g (m,) and its first-order optimality at z (n_z,)."""

    def constraint_values(self, z: np.ndarray) -> np.ndarray: ...

    def kkt(self, z: np.ndarray, nonsmooth: bool = True) -> Optimality: ...


def until_done(
    problem: Stationarity, on_iterate: Callable[[np.ndarray], None], tolerance: float, deadline: float
) -> Callable[[np.ndarray], None]:
    """The solver's callback: ``on_iterate(z)``, then StopIteration (which every solver honours) once
    the iterate is inside every aggregated constraint (up to the aggregation's margin) and its KKT
    residual is at most ``tolerance``, or ``deadline`` (``time.perf_counter``) has passed.

    Every iterate is tested: near a KKT point SLSQP's iterates move at the scale of its steps, and
    the residual with them (active aggregates of β = 300 turn their gradients fast), between 5e-4
    and 2e-2 at an objective still to 1e-5 on the G1; tested every 10th iterate, a restart ran on
    for hundreds of iterations past points that met the tolerance. The test costs a non-negative
    least squares on the active set (0.6 ms there): the gradient and Jacobian it needs at the
    iterate are those the solver asks for next. Where the criterion is non-smooth (an extreme
    singular value multiple), the Clarke test (module docstring, 0.2 s on the G1) runs every
    ``NONSMOOTH_EVERY``-th iterate."""

    count = iter(range(1 << 62))

    def callback(z: np.ndarray) -> None:
        on_iterate(z)
        if time.perf_counter() > deadline:
            raise StopIteration
        nonsmooth = next(count) % NONSMOOTH_EVERY == 0  # the Clarke test (a small SDP) every so often
        if stationary(problem, z, tolerance, nonsmooth):
            raise StopIteration

    return callback


def stationary(problem: Stationarity, z: np.ndarray, tolerance: float, nonsmooth: bool = True) -> bool:
    """Whether z (n_z,) is inside every aggregated constraint (up to the aggregation's margin) with a
    KKT residual (or Clarke's, ``nonsmooth``) of at most ``tolerance``."""
    return problem.constraint_values(z).max() <= GRID_MARGIN and problem.kkt(z, nonsmooth).residual <= tolerance
