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
from excite_cli.criterion import ConditionNumber

#: Progress hook: (restart index, SLSQP iteration, current objective value).
ProgressHook = Callable[[int, int, float], None]


@dataclass(frozen=True)
class OptimizationResult:
    """Best of the restarts.

    Attributes:
        alpha: (n, 2N+1) Fourier coefficients.
        objective: criterion value at ``alpha`` (log cond or cond).
        iterations: SLSQP iterations summed over the restarts.
        message: SLSQP's message for the best restart.
        wall_time_s: wall time of all restarts [s].
    """

    alpha: np.ndarray
    objective: float
    iterations: int
    message: str
    wall_time_s: float


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


def optimize_trajectory(
    criterion: ConditionNumber,
    constraints: Sequence[Constraint],
    options: OptimizerConfig,
    rng: np.random.Generator,
    start: Callable[[np.random.Generator], np.ndarray],
    boundary: BoundaryConditions,
    progress: Optional[ProgressHook] = None,
    warm_start: Optional[np.ndarray] = None,
) -> OptimizationResult:
    """Minimize the criterion over α from ``options.restarts`` random feasible starts.

    SLSQP works on the variables z of ``boundary`` (α = s ⊙ (w* + Z z): the boundary conditions
    hold exactly, with diagonal preconditioning s, see :mod:`excite_cli.boundary`); everything else
    sees α.

    SQP iterates approach the constraint boundary from outside, so each restart ends with the best
    of: the best point whose aggregated constraints were all ≤ 0, and the repaired last iterate
    (:func:`repair`); both are confirmed by every constraint's exact grid check.

    Args:
        criterion: the condition-number criterion (value and gradient).
        constraints: all constraints (values and Jacobians, exact checks, repairs).
        options: method, iterations, tolerance, restarts.
        rng: random generator of the starts.
        start: draws a random α (n, 2N+1) that every constraint and the boundary conditions accept.
        boundary: the boundary conditions and the optimizer's coordinates.
        progress: called after every SLSQP iteration.
        warm_start: an accepted α (n, 2N+1) to start the first restart from instead of a random one
            (the sequence passes the previous iteration's optimum).

    Returns:
        The best accepted point over all restarts.
    """
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def constraint_values(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = z.tobytes()
        if key not in cache:
            cache.clear()
            g, J = _stack(constraints, boundary.to_alpha(z))
            cache[key] = (g, boundary.chain(J))
        return cache[key]

    last_value = [np.nan]
    inside: dict[str, object] = {}

    def objective(z: np.ndarray) -> tuple[float, np.ndarray]:
        alpha = boundary.to_alpha(z)
        value, grad = criterion.value_and_gradient(alpha)
        last_value[0] = value
        if value < inside.get("value", np.inf) and constraint_values(z)[0].max() <= 0.0:
            inside.update(value=value, x=alpha.copy())
        return value, boundary.chain(grad.ravel())

    begin = time.perf_counter()
    best: Optional[tuple[float, np.ndarray, str]] = None
    total_iterations = 0
    for restart in range(options.restarts):
        x0 = warm_start.copy() if (restart == 0 and warm_start is not None) else start(rng)
        inside.clear()
        counter = [0]

        def callback(xk: np.ndarray, restart: int = restart, counter: list = counter) -> None:
            counter[0] += 1
            if progress is not None:
                progress(restart, counter[0], last_value[0])

        result = minimize(
            objective,
            boundary.to_variables(x0),
            jac=True,
            method=options.method,
            constraints=[{
                "type": "ineq",
                "fun": lambda x: -constraint_values(x)[0],
                "jac": lambda x: -constraint_values(x)[1],
            }],
            options={"maxiter": options.max_iterations, "ftol": options.tolerance},
            callback=callback,
        )
        total_iterations += int(result.nit)
        candidates = [x0, repair(constraints, boundary.to_alpha(result.x), x0, boundary)]
        if "x" in inside:
            candidates.append(np.asarray(inside["x"]))
        for alpha in candidates:
            if not _accepted(constraints, alpha):
                continue
            value = criterion.value(alpha)
            if best is None or value < best[0]:
                best = (value, alpha, str(result.message))
    assert best is not None, "the start of every restart is accepted"
    return OptimizationResult(
        alpha=best[1],
        objective=best[0],
        iterations=total_iterations,
        message=best[2],
        wall_time_s=time.perf_counter() - begin,
    )
