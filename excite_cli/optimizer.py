"""One trajectory optimization (Eq. 7 under the constraints): SLSQP from several random feasible starts.

SLSQP is scipy's sequential quadratic programming with a quasi-Newton (BFGS) Hessian, the paper's
choice of a quasi-Newton method with constraints (Section IV-A). The criterion and every constraint
supply analytic gradients.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Optional, Sequence

import numpy as np
from scipy.optimize import minimize

from excite_cli.boundary import BoundaryConditions
from excite_cli.config import OptimizerConfig
from excite_cli.constraints import Constraint
from excite_cli.criterion import Criterion

#: Progress hook: (restart index, SLSQP iteration, current objective value).
ProgressHook = Callable[[int, int, float], None]


@dataclass(frozen=True)
class RestartResult:
    """The best accepted point of one restart.

    Attributes:
        index: the restart's number within its iteration, 0-based.
        alpha: (n, 2N+1) Fourier coefficients.
        objective: criterion value at ``alpha`` (log cond or cond).
        iterations: SLSQP iterations.
        message: SLSQP's message.
        wall_time_s: wall time of the restart [s].
    """

    index: int
    alpha: np.ndarray
    objective: float
    iterations: int
    message: str
    wall_time_s: float


def best_restart(results: Sequence[RestartResult]) -> RestartResult:
    """The restart with the lowest objective; ties go to the lower index (so the choice does not
    depend on the order results arrive in)."""
    return min(results, key=lambda r: (r.objective, r.index))


def _stack(constraints: Sequence[Constraint], alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    parts = [c.evaluate(alpha) for c in constraints]
    return np.concatenate([g for g, _ in parts]), np.vstack([J for _, J in parts])


def _accepted(constraints: Sequence[Constraint], alpha: np.ndarray) -> bool:
    return all(c.accepts(alpha) for c in constraints)


def repair(constraints: Sequence[Constraint], alpha: np.ndarray, feasible: np.ndarray,
           boundary: Optional[BoundaryConditions] = None, steps: int = 12) -> np.ndarray:
    """A feasible point near α: the constraints' own exact repairs, moved back onto the boundary
    conditions, then, if some constraint still rejects it, the farthest point towards it from
    ``feasible`` (bisection on the segment, which keeps the boundary conditions: they are affine).

    Args:
        constraints: all constraints.
        alpha: (n, 2N+1) point to repair, typically the last SQP iterate.
        feasible: (n, 2N+1) point every constraint accepts (the restart's start).
        boundary: the boundary conditions both points meet, if any.
        steps: bisection steps.
    """
    for c in constraints:
        alpha = c.restore(alpha)
    if boundary is not None:
        alpha = boundary.project(alpha)
    if _accepted(constraints, alpha):
        return alpha
    lo, hi = 0.0, 1.0
    for _ in range(steps):
        mid = (lo + hi) / 2.0
        lo, hi = (mid, hi) if _accepted(constraints, feasible + mid * (alpha - feasible)) else (lo, mid)
    return feasible + lo * (alpha - feasible)


class _Evaluations:
    """SLSQP's callbacks in its variables z: the objective, and the stacked constraints evaluated once
    per point; remembers the best point whose aggregated constraints all hold.

    Attributes:
        best_value: the lowest objective at such a point (``start_value`` until one is seen).
        best_inside: its α (n, 2N+1), or None.
    """

    def __init__(self, criterion: Criterion, constraints: Sequence[Constraint], boundary: BoundaryConditions,
                 start_value: float):
        self.criterion, self.all, self.boundary = criterion, constraints, boundary
        self.best_value, self.best_inside = start_value, None
        self._cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def constraints(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Stacked values g (m,) and Jacobian in z."""
        key = z.tobytes()
        if key not in self._cache:
            self._cache.clear()
            g, J = _stack(self.all, self.boundary.to_alpha(z))
            self._cache[key] = (g, self.boundary.chain(J))
        return self._cache[key]

    def objective(self, z: np.ndarray) -> tuple[float, np.ndarray]:
        """The criterion and its gradient in z."""
        alpha = self.boundary.to_alpha(z)
        value, grad = self.criterion.value_and_gradient(alpha)
        if value < (self.best_value if self.best_inside is not None else np.inf) and self.constraints(z)[0].max() <= 0.0:
            self.best_value, self.best_inside = value, alpha.copy()
        return value, self.boundary.chain(grad.ravel())


def optimize_restart(
    criterion: Criterion,
    constraints: Sequence[Constraint],
    options: OptimizerConfig,
    start: np.ndarray,
    boundary: BoundaryConditions,
    index: int = 0,
    progress: Optional[ProgressHook] = None,
) -> RestartResult:
    """Minimize the criterion over α with SLSQP from one feasible start.

    SLSQP works on the variables z of ``boundary`` (α = s ⊙ (w* + Z z): the boundary conditions
    hold exactly, with diagonal preconditioning s, see :mod:`excite_cli.boundary`); everything else
    sees α.

    SQP iterates approach the constraint boundary from outside, so the restart ends with the best
    of: the start, the best point whose aggregated constraints were all ≤ 0, and the repaired last
    iterate (:func:`repair`); each is confirmed by every constraint's exact grid check.

    Args:
        criterion: the criterion (value and gradient).
        constraints: all constraints (values and Jacobians, exact checks, repairs).
        options: method, iterations, tolerance.
        start: (n, 2N+1) α that every constraint and the boundary conditions accept.
        boundary: the boundary conditions and the optimizer's coordinates.
        index: the restart's number (passed to ``progress`` and kept in the result).
        progress: called after every SLSQP iteration with the best value whose aggregated
            constraints all held so far (the start's until one is found).
    """
    begin = time.perf_counter()
    problem = _Evaluations(criterion, constraints, boundary, criterion.value(start))
    counter = [0]

    def callback(xk: np.ndarray) -> None:
        counter[0] += 1
        if progress is not None:
            progress(index, counter[0], problem.best_value)

    result = minimize(
        problem.objective,
        boundary.to_variables(start),
        jac=True,
        method=options.method,
        constraints=[{"type": "ineq", "fun": lambda x: -problem.constraints(x)[0], "jac": lambda x: -problem.constraints(x)[1]}],
        options={"maxiter": options.max_iterations, "ftol": options.tolerance},
        callback=callback,
    )
    candidates = [start, repair(constraints, boundary.to_alpha(result.x), start, boundary)]
    if problem.best_inside is not None:
        candidates.append(problem.best_inside)
    scored = [(criterion.value(alpha), k, alpha) for k, alpha in enumerate(candidates) if k == 0 or _accepted(constraints, alpha)]
    value, _, alpha = min(scored, key=lambda item: item[:2])
    return RestartResult(index, alpha, value, int(result.nit), str(result.message), time.perf_counter() - begin)
