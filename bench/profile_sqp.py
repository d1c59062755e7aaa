"""Where one SQP iteration's time goes, and what BLAS threads cost.

Runs one restart of SLSQP on a problem (default configs/g1_arms.yaml, 60 iterations) with every
evaluation timed: the criterion (value and analytic gradient), each constraint's values and
Jacobian, the exact checks and repairs at the end, and SLSQP's own work (its QP subproblem and
bookkeeping: the rest of the wall time). Then times one analytic gradient and one-sided finite
differences with the machine's default BLAS threads and with one thread (threadpoolctl).

Run: `.venv/bin/python bench/profile_sqp.py [CONFIG] [ITERATIONS]`. Prints tables; asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_info, threadpool_limits

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import finite_difference_gradient
from excite_cli.memory import keep_freed_memory
from excite_cli.search.optimizer import optimize_restart

ROOT = Path(__file__).resolve().parent.parent


def timed(owner: object, method: str, label: str, spent: dict, calls: dict) -> None:
    """Replace ``owner.method`` by a version adding its wall time to ``spent[label]``."""
    inner = getattr(owner, method)

    def wrapper(*args, **kwargs):
        start = time.perf_counter()
        try:
            return inner(*args, **kwargs)
        finally:
            spent[label] += time.perf_counter() - start
            calls[label] += 1

    setattr(owner, method, wrapper)


def profile(config: Path, iterations: int) -> None:
    problem = load_problem(config)
    problem.optimizer.max_iterations = iterations
    excitation = build_excitation(problem)
    criterion = excitation.criterion()
    spent: dict[str, float] = defaultdict(float)
    calls: dict[str, int] = defaultdict(int)
    timed(criterion, "value_and_gradient", "criterion + gradient", spent, calls)
    timed(criterion, "value", "criterion value (final choice)", spent, calls)
    for c in excitation.constraints:
        timed(c, "evaluate", f"{c.name}: values + Jacobian", spent, calls)
        timed(c, "check_samples", f"{c.name}: exact checks", spent, calls)
    start_alpha = excitation.random_start(np.random.default_rng(0))
    keep_freed_memory()  # as every process that runs restarts (excite_cli.search.engine)
    with threadpool_limits(limits=1):
        start = time.perf_counter()
        result = optimize_restart(
            criterion, excitation.constraints, problem.optimizer, start_alpha, excitation.boundary
        )
        wall = time.perf_counter() - start
    its = max(result.iterations, 1)
    print(
        f"{config.name}: {result.iterations} SLSQP iterations, {calls['criterion + gradient']} evaluations, "
        f"{wall:.1f} s wall, {1e3 * wall / its:.1f} ms per iteration"
    )
    print(f"{'part':<36} {'calls':>6} {'ms/call':>8} {'ms/iteration':>13} {'share':>6}")
    for label, seconds in sorted(spent.items(), key=lambda item: -item[1]):
        print(
            f"{label:<36} {calls[label]:>6} {1e3 * seconds / calls[label]:>8.2f} {1e3 * seconds / its:>13.2f} {seconds / wall:>6.0%}"
        )
    rest = wall - sum(spent.values())
    print(f"{'SLSQP itself (QP, line search)':<36} {'':>6} {'':>8} {1e3 * rest / its:>13.2f} {rest / wall:>6.0%}")


def threads(config: Path) -> None:
    problem = load_problem(config)
    problem.optimizer.objective = "cond"
    excitation = build_excitation(problem)
    criterion = excitation.criterion()
    alpha = excitation.limits.random_start(excitation.trajectory.n_coefficients, np.random.default_rng(0), 0.7)
    default = max((pool["num_threads"] for pool in threadpool_info()), default=1)
    print(f"\n{'BLAS threads':<14} {'analytic gradient [ms]':>23} {'one-sided FD [s]':>17}")
    for limit in (None, 1):
        with threadpool_limits(limits=limit):
            criterion.value_and_gradient(alpha)
            times = []
            for _ in range(30):
                start = time.perf_counter()
                criterion.value_and_gradient(alpha)
                times.append(time.perf_counter() - start)
            start = time.perf_counter()
            finite_difference_gradient(criterion, alpha, 1e-6, central=False)
            fd = time.perf_counter() - start
        print(f"{default if limit is None else limit:<14} {1e3 * np.median(times):>23.2f} {fd:>17.3f}")


if __name__ == "__main__":
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "configs" / "g1_arms.yaml"
    profile(path, int(sys.argv[2]) if len(sys.argv) > 2 else 60)
    threads(path)
