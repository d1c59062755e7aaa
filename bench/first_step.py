"""How far the first quasi-Newton step may go: restarts of one problem with the criterion scaled so
that the first step moves no joint by more than FIRST_STEP of its half-range
(:func:`excite_cli.search.solvers.criterion_scale`), for several values of it.

The same random starts for every value (iteration 1 of the config's seed, restarts 0 … R−1), one
process, one BLAS thread; prints per value and restart the end value, the solver iterations, the stop
reason, the KKT residual, which end point was kept and the wall time. The default 0.1 keeps every
UR10 lab start from failing; larger values end lower on the G1 (how-it-works, "The criterion's scale").

    .venv/bin/python bench/first_step.py configs/ur10_lab.yaml --steps 0.1 0.3 1.0 --restarts 6
    .venv/bin/python bench/first_step.py configs/g1_arms.yaml --objective log_cond --iterations 200

Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from excite_cli.config_file import load_problem, with_overrides
from excite_cli.design.resolve import build_excitation
from excite_cli.memory import keep_freed_memory
from excite_cli.search import solvers
from excite_cli.search.restarts import RestartTask


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("config", type=Path)
    parser.add_argument("--steps", type=float, nargs="+", default=[0.1, 0.3, 1.0])
    parser.add_argument("--restarts", type=int, default=2)
    parser.add_argument("--objective", default="log_det")
    parser.add_argument("--iterations", type=int, default=400)
    args = parser.parse_args()
    keep_freed_memory()
    problem = load_problem(args.config)
    problem = with_overrides(
        problem, {"optimizer.objective": args.objective, "optimizer.max_iterations": args.iterations}
    )
    excitation = build_excitation(problem)
    print("| first step | restart | end value | iterations | stop | KKT residual | end point | wall [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for step in args.steps:
        solvers.FIRST_STEP = step
        for index in range(args.restarts):
            with threadpool_limits(limits=1):
                task = RestartTask(1, index, problem.optimizer.seed, np.zeros((0, excitation.columns)))
                r = task(excitation)
            print(
                f"| {step} | {index} | {r.objective:.4f} | {r.iterations} | {r.stop} | "
                f"{r.optimality.residual:.1e} | {r.end} | {r.wall_time_s:.0f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
