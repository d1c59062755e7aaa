"""Is the G1's slow convergence the aggregates' stiffness? One restart per seed (iteration 1,
restart 0, as `excite optimize` draws it), SLSQP on the criterion scaled as `optimizer.method` runs it,
with every smooth maximum's sharpness β (constraints/lse.py) set to each value given; every
``--every`` iterations the KKT residual of the iterate (at that β) is computed. Prints per (β, seed)
the iteration at which the residual first met ``optimizer.optimality_tolerance``, the criterion there
and at the end, and the wall time; one BLAS thread, one restart at a time in this process.

    .venv/bin/python bench/sharpness.py configs/g1_arms.yaml --betas 100 150 300 --seeds 0 1 --iterations 800

Asserts nothing. A smaller β over-estimates each maximum more (by up to log(count)/β of a half-range),
so the optimum it reaches is a little more conservative.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

import excite_cli.constraints.lse as lse
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.memory import keep_freed_memory
from excite_cli.search.kkt import kkt_optimality
from excite_cli.search.nlp import Evaluations
from excite_cli.search.restarts import RestartTask
from excite_cli.search.solvers import solve


def first_converged(excitation, seed: int, iterations: int, every: int, tolerance: float) -> tuple:
    """(iteration at which the KKT residual first met ``tolerance`` or None, criterion there, criterion
    at the end, wall time [s]) of one restart at the current β."""
    criterion = excitation.criterion(np.zeros((0, excitation.base.count)))
    start = excitation.random_start(RestartTask(1, 0, seed, np.zeros((0, excitation.base.count))).rng())
    problem = Evaluations(criterion, excitation.constraints, excitation.boundary, criterion.value(start))
    seen, met = [0], [None, np.nan]
    begin = time.perf_counter()

    def hook(z: np.ndarray) -> None:
        seen[0] += 1
        if met[0] is None and seen[0] % every == 0:
            if kkt_optimality(problem.gradient(z), *problem.constraints(z)).residual <= tolerance:
                met[:] = [seen[0], problem.value(z)]

    run = solve("SLSQP", problem, excitation.boundary.to_variables(start), iterations, 1e-6, hook)
    return met[0], met[1], problem.value(run.z), time.perf_counter() - begin


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("config", type=Path)
    parser.add_argument("--betas", type=float, nargs="+", default=[100.0, 150.0, lse.SHARPNESS])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--iterations", type=int, default=800)
    parser.add_argument("--every", type=int, default=25)
    args = parser.parse_args()
    keep_freed_memory()
    threadpool_limits(limits=1)
    problem = load_problem(args.config)
    excitation = build_excitation(problem)
    tolerance = problem.optimizer.optimality_tolerance
    print("| β | seed | KKT ≤ tolerance at iteration | criterion there | criterion at the end | wall [s] |")
    print("|---|---|---|---|---|---|")
    for beta in args.betas:
        lse.SHARPNESS = beta  # smooth_max reads it at each call
        for seed in args.seeds:
            at, there, end, wall = first_converged(excitation, seed, args.iterations, args.every, tolerance)
            print(f"| {beta:g} | {seed} | {at or 'not met'} | {there:.4f} | {end:.4f} | {wall:.0f} |", flush=True)


if __name__ == "__main__":
    main()
