"""The solvers of ``optimizer.method`` compared on one problem: the same restarts (same seeds, same
analytic gradients and Jacobians, same projection of the last iterate), one restart per
(method, seed) in this process with one BLAS thread; prints the start and end value, the KKT
residual at the end point, the stop reason, the solver's iterations and the wall time.

    .venv/bin/python bench/solvers.py configs/g1_arms.yaml --seeds 0 4 --iterations 200
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from excite_cli.config_file import load_problem, with_overrides
from excite_cli.design.resolve import build_excitation
from excite_cli.memory import keep_freed_memory
from excite_cli.search.restarts import RestartTask
from excite_cli.search.solvers import METHODS


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("config", type=Path)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 4])
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--iterations", type=int, default=200)
    args = parser.parse_args()
    keep_freed_memory()
    threadpool_limits(limits=1)
    print("| method | seed | start cond | end cond | KKT residual | stop | end point | iterations | wall [s] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for method in args.methods:
        problem = with_overrides(
            load_problem(args.config),
            {
                "optimizer.method": method,
                "optimizer.max_iterations": args.iterations,
                "optimizer.objective": "log_cond",
            },
        )
        excitation = build_excitation(problem)
        for seed in args.seeds:
            begin = time.perf_counter()
            r = RestartTask(1, 0, seed, np.zeros((0, excitation.base.count)))(excitation)
            print(
                f"| {method} | {seed} | {np.exp(r.start_objective):.1f} | {np.exp(r.objective):.2f} | {r.optimality.residual:.1e} | "
                f"{r.stop} | {r.end} | {r.iterations} | {time.perf_counter() - begin:.1f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
