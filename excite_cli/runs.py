"""One library function per study a command runs: ``optimize`` (its result written after every
iteration, resumable), ``compare-random`` and ``verify-gradient``. They check their output paths
before computing; the command line only parses options and prints what they return."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional, Sequence

import numpy as np
import yaml

from excite_cli.config import Problem, effective_yaml, with_overrides
from excite_cli.identification.config import IdentifyProblem
from excite_cli.criterion import OBJECTIVES
from excite_cli.engine import Engine, default_workers
from excite_cli.errors import ExciteError, Interrupted
from excite_cli.excitation import Excitation, build_excitation
from excite_cli.identification.pipeline import run_identification, write_identified_urdf
from excite_cli.optimizer import ProgressHook
from excite_cli.identification.report_file import write_identification
from excite_cli.output import open_result, read_iterations, read_prior, read_table, results_table, write_result
from excite_cli.identification.figures import plot_identification, plot_ladder
from excite_cli.plots import plot_comparison, plot_result
from excite_cli.random_baseline import draw_pool, greedy_selection, pool_convergence
from excite_cli.sequence import IterationResult, describe, run_sequence
from excite_cli.targets import check_target
from excite_cli.verify import GradientCheck, check_gradient, constraint_jacobian_error

#: Fields that may differ between a result and the run that resumes it (they do not change results).
RESUMABLE_CHANGES = ("sequence.iterations", "optimizer.workers", "optimizer.scheduler")


def engine_for(problem: Problem, excitation: Excitation) -> Engine:
    """Where restarts and draws run: ``optimizer.scheduler``, else ``optimizer.workers`` local
    processes (default: the machine's cores)."""
    return Engine(excitation, problem.optimizer.workers or default_workers(), problem.optimizer.scheduler)


@dataclass
class OptimizeRun:
    """A finished ``optimize``: the problem, its iterations, the result file and the plots."""

    excitation: Excitation
    results: list[IterationResult]
    target: Path
    plots: list[Path]


def run_optimize(problem: Problem, target: Path, force: bool = False, resume: bool = False,
                 progress: Optional[Callable[[int], ProgressHook]] = None,
                 on_iteration: Optional[Callable[[IterationResult], None]] = None,
                 engine: Optional[Engine] = None) -> OptimizeRun:
    """The sequential generation of ``problem``, writing ``target`` after every iteration, then plots.

    Args:
        force: replace an existing ``target``.
        resume: continue the iterations already in ``target`` (made with the same config, up to
            ``RESUMABLE_CHANGES``); the end result is that of an uninterrupted run.
        progress, on_iteration: see :func:`run_sequence`.
        engine: where restarts run (default: :func:`engine_for`).

    Raises:
        ExciteError: bad target, prior data or problem; a result to resume made with another config.
        Interrupted: Ctrl-C; the finished iterations are in ``target``.
    """
    check_target(target, "--output", force, exists_ok=resume)
    if resume and not target.is_file():
        raise ExciteError(f"--resume: no result at {target} to continue")
    excitation = build_excitation(problem)
    prior = read_prior(problem.resolve(problem.sequence.prior), excitation.base) if problem.sequence.prior else None
    finished = _resumable(target, excitation, prior) if resume else []
    written = list(finished)

    def done(result: IterationResult) -> None:
        written.append(result)
        write_result(target, excitation, written, problem.optimizer.seed, {"method": "optimized"})
        if on_iteration:
            on_iteration(result)

    try:
        with engine or engine_for(problem, excitation) as active:
            results = run_sequence(excitation, problem.sequence.iterations, problem.optimizer.seed, prior, progress,
                                   done, active, finished)
    except KeyboardInterrupt:
        raise Interrupted(target, len(written)) from None
    return OptimizeRun(excitation, results, target, plot_result(target, excitation, results))


def _resumable(target: Path, excitation: Excitation, prior: Optional[np.ndarray]) -> list[IterationResult]:
    """The iterations of ``target`` if it was made with the same config (see ``RESUMABLE_CHANGES``)."""
    with open_result(target, "--resume") as f:
        stored = yaml.safe_load(str(f.attrs.get("config", ""))) or {}
    current = yaml.safe_load(effective_yaml(excitation.problem))
    for dotted in RESUMABLE_CHANGES:
        section, name = dotted.split(".")
        for config in (stored, current):
            config.get(section, {}).pop(name, None)
    if stored != current:
        differing = sorted(k for k in set(stored) | set(current) if stored.get(k) != current.get(k))
        raise ExciteError(f"--resume: {target} was made with another config ({', '.join(differing) or 'the whole file'} differ)")
    finished = read_iterations(target, excitation, prior)
    if len(finished) > excitation.problem.sequence.iterations:
        raise ExciteError(f"--resume: {target} has {len(finished)} iterations, more than the {excitation.problem.sequence.iterations} asked for")
    return finished


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


def run_compare_random(problem: Problem, optimized: Optional[Path], target: Optional[Path], equal_effort: bool = False,
                       force: bool = False, progress: Optional[Callable[[int], ProgressHook]] = None,
                       draws: Optional[Callable[[int, int], None]] = None) -> Comparison:
    """The conventional baseline (ref. [16], Table II) against an optimized result: random feasible
    candidates (``random_baseline.pool_size``, or for as long as the optimizer took with
    ``equal_effort``), greedy selection, written to ``target`` in the optimize schema.

    Args:
        optimized: an optimize result of the same problem; None runs ``optimize`` first into
            ``<output>_optimized.h5``.
        target: the random selection's result (default ``<output>_random.h5``).
        progress: the optimize progress (when it runs); draws: called with (kept, drawn).

    Raises:
        ExciteError: bad paths, a result of another problem, too few feasible candidates.
    """
    base = Path(problem.output)
    target = check_target(target or base.with_name(base.stem + "_random.h5"), "--output", force)
    excitation = build_excitation(problem)
    with engine_for(problem, excitation) as engine:
        if optimized is None:  # run here: its table is in memory
            run = run_optimize(problem, base.with_name(base.stem + "_optimized.h5"), force, progress=progress, engine=engine)
            optimized_table, optimized_time = results_table(run.results), sum(r.wall_time_s for r in run.results)
        else:
            optimized_table, optimized_time = read_table(optimized, "--optimized")
            _check_same_problem(optimized, excitation)
        count = len(optimized_table)
        rcfg = problem.random_baseline
        if not equal_effort and rcfg.pool_size < count:
            raise ExciteError(f"random_baseline.pool_size: {rcfg.pool_size} candidates cannot fill {count} iterations")
        drawn = draw_pool(engine, None if equal_effort else rcfg.pool_size, rcfg.seed,
                          optimized_time if equal_effort else None, draws)
    if len(drawn.alphas) < count:
        raise ExciteError(f"random_baseline: only {len(drawn.alphas)} feasible candidates of {drawn.drawn} drawn; "
                          f"{count} are needed (enlarge the pool or the time)")
    begin = time.perf_counter()
    chosen, _ = greedy_selection(drawn.regressors, count)
    selection_s = time.perf_counter() - begin
    stacked = np.zeros((0, excitation.base.count))
    results = []
    for k, index in enumerate(chosen, start=1):
        results.append(describe(excitation, k, drawn.alphas[index], stacked))
        stacked = np.vstack([stacked, results[-1].regressor])
    write_result(target, excitation, results, rcfg.seed, {"method": "random_selection", "pool_size": len(drawn.alphas),
                                                          "drawn": drawn.drawn, "generation_time_s": drawn.generation_time_s,
                                                          "selection_time_s": selection_s})
    random_table = results_table(results)
    sizes = sorted({s for s in (count, 10, 30, 100, 300, 1000, 3000, len(drawn.alphas)) if count <= s <= len(drawn.alphas)})
    plot = plot_comparison(target.with_suffix("").with_name(target.stem + "_comparison.png"), random_table, optimized_table)
    return Comparison(random_table, optimized_table, drawn.generation_time_s + selection_s, optimized_time, len(drawn.alphas),
                      drawn.drawn, pool_convergence(drawn.regressors, count, sizes), target, plot)


def _check_same_problem(path: Path, excitation: Excitation) -> None:
    """Raise unless the result at ``path`` has the robot joints and Fourier size of ``excitation``."""
    with open_result(path, "--optimized") as f:
        joints = [str(j.decode() if isinstance(j, bytes) else j) for j in f["robot/joint_names"][()]] if "robot" in f else []
        shape = f["iterations"][sorted(f["iterations"].keys(), key=int)[0]]["alpha"].shape if len(f.get("iterations", {})) else None
    if joints != excitation.robot.joint_names or shape != (excitation.robot.n_joints, excitation.trajectory.n_coefficients):
        raise ExciteError(f"--optimized: {path} was made for another problem (joints {joints}, alpha shape {shape})")


@dataclass
class Verification:
    """``verify-gradient``: (point, objective, check) per row; (constraint, rows, error) per constraint."""

    gradients: list[tuple[str, str, GradientCheck]]
    jacobians: list[tuple[str, int, float]]

    @property
    def worst(self) -> float:
        """The largest relative error against central differences."""
        return max([c.error_central for _, _, c in self.gradients] + [e for _, _, e in self.jacobians])


def run_verify(problem: Problem, result: Optional[Path] = None, objectives: Sequence[str] = OBJECTIVES,
               step: float = 1e-6, seed: int = 0) -> Verification:
    """Every criterion's analytic gradient against finite differences at a random feasible α (and at
    the last optimum of ``result``, with the earlier iterations as C₀), and every constraint's
    Jacobian against central differences at a livelier α.

    Raises:
        ExciteError: an unknown objective, a bad step, a result of another problem.
    """
    for name in objectives:
        if name not in OBJECTIVES:
            raise ExciteError(f"--objective: '{name}' is not a criterion; expected one of {', '.join(OBJECTIVES)}")
    if seed < 0:
        raise ExciteError(f"--seed: must be ≥ 0 (got {seed})")
    if not 1e-12 <= step <= 1e-2:
        raise ExciteError(f"--step: {step:g} is not a finite-difference step for coefficients in rad; use 1e-12 to 1e-2")
    excitation = build_excitation(problem)
    m = excitation.trajectory.n_coefficients
    points = [("random", None, excitation.limits.random_start(m, np.random.default_rng(seed), fill=0.7))]
    if result is not None:
        finished = read_iterations(result, excitation, field="--result")
        stacked = np.vstack([np.zeros((0, excitation.base.count)), *[r.regressor for r in finished[:-1]]])
        points.append((f"optimum {finished[-1].index}", stacked, finished[-1].alpha))
    gradients = []
    for label, prior, alpha in points:
        for name in objectives:
            criterion = excitation.criterion(prior, name)
            gradients.append((label, name, check_gradient(criterion, alpha, step=step)))
    lively = excitation.limits.random_start(m, np.random.default_rng(seed), 0.9, excitation.home)
    jacobians = [(c.name, c.evaluate(lively)[0].size, constraint_jacobian_error(c, lively)) for c in excitation.constraints]
    return Verification(gradients, jacobians)


@dataclass
class IdentifyRun:
    """``identify``: the report, the robot, the files written (report, plots) and the URDF round-trip
    deviation [Nm]."""

    report: object
    robot: object
    target: Path
    plots: list[Path]
    urdf_deviation: Optional[float]


def run_identify(problem: IdentifyProblem, target: Path, urdf_out: Optional[Path] = None, force: bool = False) -> IdentifyRun:
    """Identify (:func:`run_identification`), write the report (HDF5), the residual plot and, with
    ``urdf_out``, the identified URDF (physical consistency is then fitted too).

    Raises:
        ExciteError: bad paths or data (see :func:`run_identification`).
    """
    check_target(target, "--output", force)
    if urdf_out is not None:
        check_target(urdf_out, "--urdf-out", force)
        problem = with_overrides(problem, {"identification.physical_consistency": True})
    report, robot, base, regressor = run_identification(problem)
    write_identification(target, report, robot, base, problem, regressor)
    deviation = write_identified_urdf(problem, report, robot, base, urdf_out) if urdf_out is not None else None
    stem = target.with_suffix("")
    plots = [plot_identification(stem.with_name(target.stem + "_residuals.png"), report),
             plot_ladder(stem.with_name(target.stem + "_ladder.png"), report)]
    return IdentifyRun(report, robot, target, plots, deviation)
