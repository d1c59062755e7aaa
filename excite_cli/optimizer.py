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

from excite_cli.config import OptimizerConfig
from excite_cli.constraints import Constraint, JointLimits
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


def _stack(constraints: Sequence[Constraint], x: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    parts = [c.evaluate(x.reshape(shape)) for c in constraints]
    return np.concatenate([g for g, _ in parts]), np.vstack([J for _, J in parts])


def optimize_trajectory(
    criterion: ConditionNumber,
    limits: JointLimits,
    constraints: Sequence[Constraint],
    options: OptimizerConfig,
    rng: np.random.Generator,
    progress: Optional[ProgressHook] = None,
) -> OptimizationResult:
    """Minimize the criterion over α from ``options.restarts`` random feasible starts.

    Args:
        criterion: the condition-number criterion (value and gradient).
        limits: the joint limits; also draw the random feasible starts.
        constraints: all constraints, joint limits included.
        options: method, iterations, tolerance, restarts.
        rng: random generator of the starts.
        progress: called after every SLSQP iteration.

    Returns:
        The lowest criterion value among the evaluated points whose constraints hold on the grid.
    """
    n = len(criterion.robot.joint_names)
    shape = (n, criterion.basis.q.shape[1])
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def constraint_values(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = _stack(constraints, x, shape)
        return cache[key]

    last_value = [np.nan]
    best_feasible: dict[str, object] = {}

    def objective(x: np.ndarray) -> tuple[float, np.ndarray]:
        value, grad = criterion.value_and_gradient(x.reshape(shape))
        last_value[0] = value
        if value < best_feasible.get("value", np.inf) and all(c.accepts(x.reshape(shape)) for c in constraints):
            best_feasible.update(value=value, x=x.copy())
        return value, grad.ravel()

    start = time.perf_counter()
    best: Optional[tuple[float, np.ndarray, str]] = None
    total_iterations = 0
    for restart in range(options.restarts):
        x0 = limits.random_start(shape[1], rng, fill=rng.uniform(0.5, 0.9)).ravel()
        best_feasible.clear()
        counter = [0]

        def callback(xk: np.ndarray, restart: int = restart, counter: list = counter) -> None:
            counter[0] += 1
            if progress is not None:
                progress(restart, counter[0], last_value[0])

        result = minimize(
            objective,
            x0,
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
        # SQP iterates approach the boundary from outside: repair the last one where the
        # constraints can, then keep the best feasible point evaluated (x0 always is one).
        repaired = result.x.reshape(shape)
        for c in constraints:
            repaired = c.restore(repaired)
        objective(repaired.ravel())
        candidate = (float(best_feasible["value"]), np.asarray(best_feasible["x"]).reshape(shape), str(result.message))
        if best is None or candidate[0] < best[0]:
            best = candidate
    assert best is not None
    return OptimizationResult(
        alpha=best[1],
        objective=best[0],
        iterations=total_iterations,
        message=best[2],
        wall_time_s=time.perf_counter() - start,
    )
