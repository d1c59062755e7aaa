"""``compare-random``: the conventional baseline (ref. [16], Table II) beside an optimized result."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from excite_cli.config import Problem
from excite_cli.design.excitation import Excitation
from excite_cli.design.resolve import build_excitation
from excite_cli.errors import ExciteError
from excite_cli.h5 import open_h5, read_strings
from excite_cli.plots.comparison import plot_comparison
from excite_cli.search.optimizer import ProgressHook
from excite_cli.search.random_baseline import draw_pool, greedy_selection, pool_convergence
from excite_cli.search.sequence import describe
from excite_cli.storage.paths import check_target, output_lock
from excite_cli.storage.results import check_base, read_table, results_table, write_result
from excite_cli.workflows.optimize import engine_for, run_optimize


@dataclass
class Comparison:
    """``compare-random``: the random selection (Table II) beside the optimized run (Table I).

    Attributes:
        random_table, optimized_table: (iteration, cond_own, cond_stacked) rows.
        random_time_s, optimized_time_s: wall times [s] (random: drawing and selection).
        pool, drawn: feasible candidates kept, and drawn in all.
        convergence: (pool size, greedy cond(C) per step) for growing pools.
        target, plot: the random result file and the comparison figure.
    """

    random_table: np.ndarray
    optimized_table: np.ndarray
    random_time_s: float
    optimized_time_s: float
    pool: int
    drawn: int
    convergence: list[tuple[int, list[float]]]
    target: Path
    plot: Path


def run_compare_random(
    problem: Problem,
    optimized: Optional[Path],
    target: Optional[Path],
    equal_effort: bool = False,
    force: bool = False,
    progress: Optional[Callable[[int], ProgressHook]] = None,
    draws: Optional[Callable[[int, int], None]] = None,
) -> Comparison:
    """The conventional baseline (ref. [16], Table II) against an optimized result: random feasible
    candidates (``random_baseline.pool_size``, or for as long as the optimizer took with
    ``equal_effort``), greedy selection, written to ``target`` in the optimize schema.

    Args:
        optimized: an optimize result of the same problem; None runs ``optimize`` first into
            ``<output>_optimized.h5``.
        target: the random selection's result (default ``<output>_random.h5``).
        progress: the optimize progress (when it runs); draws: called with (kept, drawn).

    Raises:
        ExciteError: bad paths, a result of another problem, too few feasible candidates, another
            run writing ``target``.
    """
    base = Path(problem.output)
    target = check_target(target or base.with_name(base.stem + "_random.h5"), "output", force)
    figure = check_target(target.with_suffix("").with_name(target.stem + "_comparison.png"), "output", force=True)
    excitation = build_excitation(problem)
    with output_lock(target, "output"), engine_for(problem, excitation) as engine:
        if optimized is None:  # run here: its table is in memory
            run = run_optimize(
                problem, base.with_name(base.stem + "_optimized.h5"), force, progress=progress, engine=engine
            )
            optimized_table, optimized_time = results_table(run.results), sum(r.wall_time_s for r in run.results)
        else:
            optimized_table, optimized_time = read_table(optimized, "optimized")
            _check_same_problem(optimized, excitation)
        count = len(optimized_table)
        rcfg = problem.random_baseline
        if not equal_effort and rcfg.pool_size < count:
            raise ExciteError(
                "random_baseline.pool_size", f"{rcfg.pool_size} candidates cannot fill {count} iterations"
            )
        drawn = draw_pool(
            engine, None if equal_effort else rcfg.pool_size, rcfg.seed, optimized_time if equal_effort else None, draws
        )
    if len(drawn.alphas) < count:
        raise ExciteError(
            "random_baseline",
            f"only {len(drawn.alphas)} feasible candidates of {drawn.drawn} drawn; "
            f"{count} are needed (enlarge the pool or the time)",
        )
    begin = time.perf_counter()
    chosen, _ = greedy_selection(drawn.regressors, count)
    selection_s = time.perf_counter() - begin
    results = []
    for k, index in enumerate(chosen, start=1):
        results.append(describe(excitation, k, drawn.alphas[index], earlier=results))
    write_result(
        target,
        excitation,
        results,
        rcfg.seed,
        {
            "method": "random_selection",
            "pool_size": len(drawn.alphas),
            "drawn": drawn.drawn,
            "generation_time_s": drawn.generation_time_s,
            "selection_time_s": selection_s,
        },
    )
    random_table = results_table(results)
    sizes = sorted(
        {s for s in (count, 10, 30, 100, 300, 1000, 3000, len(drawn.alphas)) if count <= s <= len(drawn.alphas)}
    )
    plot = plot_comparison(figure, random_table, optimized_table)
    return Comparison(
        random_table,
        optimized_table,
        drawn.generation_time_s + selection_s,
        optimized_time,
        len(drawn.alphas),
        drawn.drawn,
        pool_convergence(drawn.regressors, count, sizes),
        target,
        plot,
    )


def _check_same_problem(path: Path, excitation: Excitation) -> None:
    """Raise unless the result at ``path`` has the robot joints and Fourier size of ``excitation``."""
    with open_h5(path, "optimized") as f:
        joints = read_strings(f["robot"], "joint_names") if "robot/joint_names" in f else []
        shape = (
            f["iterations"][sorted(f["iterations"].keys(), key=int)[0]]["alpha"].shape
            if len(f.get("iterations", {}))
            else None
        )
    if joints != excitation.robot.joint_names or shape != (
        excitation.robot.n_joints,
        excitation.trajectory.n_coefficients,
    ):
        raise ExciteError(
            "optimized",
            f"{path} was made for another problem (joints {joints}, alpha shape {shape})",
            path,
            "a result of the same robot joints and harmonics",
        )
    with open_h5(path, "optimized") as f:
        check_base(f, excitation.base, "optimized", path)
