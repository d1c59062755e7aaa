"""Command line: parses arguments and calls the library; every command can be done from Python too."""

from __future__ import annotations

import functools
from enum import Enum
import time
from pathlib import Path
from typing import Callable, Optional

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from excite_cli.config import IdentifyProblem, Problem, SimulationConfig, load_problem
from excite_cli.criterion import OBJECTIVES
from excite_cli.errors import ExciteError
from excite_cli.excitation import Excitation, build_excitation
from excite_cli.export import FORMATS, export_trajectory, write_export

ExportFormat = Enum("ExportFormat", {name: name for name in FORMATS}, type=str)
from excite_cli.identification.effects import UNITS as EFFECT_UNITS
from excite_cli.identification.physical import body_properties, pseudo_inertia
from excite_cli.identification.pipeline import effect_values, run_identification, write_identified_urdf
from excite_cli.identification.simulate import simulate_runs
from excite_cli.identification.validate import validate_model
from excite_cli.output import read_last_alpha, read_prior, read_table, write_identification, write_result
from excite_cli.plots import plot_comparison, plot_identification, plot_result
from excite_cli.random_baseline import draw_pool, greedy_selection, pool_convergence
from excite_cli.engine import Engine, default_workers
from excite_cli.sequence import IterationResult, describe, run_sequence
from excite_cli.verify import check_gradient, constraint_jacobian_error

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Persistently exciting trajectories for robot dynamic identification (Ayusawa et al. 2017).",
)
out = Console()
err = Console(stderr=True)


def _user_errors(command: Callable) -> Callable:
    """Turn ExciteError into one line on stderr and exit status 2 (no traceback)."""

    @functools.wraps(command)
    def wrapper(*args, **kwargs):
        try:
            return command(*args, **kwargs)
        except ExciteError as exc:
            err.print(f"[bold red]error:[/] {escape(str(exc))}", highlight=False, soft_wrap=True)
            raise typer.Exit(2) from None

    return wrapper


def _table(results: list[IterationResult]) -> Table:
    table = Table(title="Condition numbers (Table I)")
    extra = [(key, label) for key, label in (("com_max_excursion_m", "CoM [cm]"), ("min_capsule_distance_m", "dist [cm]"))
             if results and key in results[0].checks]
    for column in ("iter", "cond(C(i))", "cond(C)", "max viol.", *[label for _, label in extra], "in/out [s]", "time [s]"):
        table.add_column(column, justify="right")
    for r in results:
        ok = float(r.checks.get("transition_max_violation", -np.inf)) <= 0.0
        transitions = f"{r.checks.get('transition_in_s', 0.0):.1f}/{r.checks.get('transition_out_s', 0.0):.1f}" if ok else "violated"
        table.add_row(
            str(r.index), f"{r.cond_own:.1f}", f"{r.cond_stacked:.1f}", f"{r.max_violation:+.1e}",
            *[f"{100 * float(r.checks[key]):.2f}" for key, _ in extra], transitions, f"{r.wall_time_s:.0f}",
        )
    table.caption = "in/out: quintic transitions from and to the home posture at rest (checked on the fine grid)"
    return table


def _override_engine(problem: Problem, workers: Optional[int], scheduler: Optional[str]) -> None:
    """Apply ``--workers`` / ``--scheduler`` to the config."""
    if workers is not None:
        problem.optimizer.workers = workers
    if scheduler is not None:
        problem.optimizer.scheduler = scheduler


def _engine(problem: Problem, excitation: Excitation) -> Engine:
    """Where the restarts and random draws run: ``optimizer.scheduler``, else ``optimizer.workers``
    local processes (default: the machine's cores)."""
    return Engine(excitation, problem.optimizer.workers or default_workers(), problem.optimizer.scheduler)


def _optimize(problem: Problem, excitation: Excitation, target: Path, engine: Engine) -> list[IterationResult]:
    """Run the sequential generation with a progress bar, writing ``target`` after every iteration.
    Ctrl-C keeps the finished iterations and exits with status 130."""
    prior = read_prior(problem.resolve(problem.sequence.prior), excitation.base) if problem.sequence.prior else None
    err.print(
        f"{len(excitation.robot.joint_names)} active joints, {excitation.base.count} base parameters, "
        f"{excitation.trajectory.n_coefficients * excitation.robot.n_joints} Fourier coefficients, "
        f"{len(excitation.constraints)} constraint(s), {0 if prior is None else prior.shape[0]} prior rows",
        highlight=False,
    )
    finished: list[IterationResult] = []
    opts = problem.optimizer
    with Progress(
        TextColumn("{task.description}"), BarColumn(), TextColumn("{task.fields[status]}"), TimeElapsedColumn(),
        console=err, transient=False,
    ) as bar:
        tasks = {
            k: bar.add_task(f"iteration {k}", total=opts.restarts * opts.max_iterations, status="waiting")
            for k in range(1, problem.sequence.iterations + 1)
        }

        def progress(k: int):
            steps: dict[int, int] = {}

            def hook(restart: int, it: int, value: float) -> None:
                steps[restart] = it
                c = np.exp(value) if opts.objective == "log_cond" else value
                bar.update(tasks[k], completed=sum(steps.values()),
                           status=f"restart {restart + 1}/{opts.restarts} · cond {c:.1f}")
            return hook

        def done(result: IterationResult) -> None:
            finished.append(result)
            write_result(target, excitation, finished, opts.seed, {"method": "optimized"})
            bar.update(tasks[result.index], completed=opts.restarts * opts.max_iterations,
                       status=f"cond(C) {result.cond_stacked:.1f}")
            if not err.is_terminal:  # logs get a line per iteration instead of a live bar
                err.print(f"iteration {result.index}: cond(C(i)) {result.cond_own:.1f}, cond(C) {result.cond_stacked:.1f}, "
                          f"{result.wall_time_s:.0f} s", highlight=False)

        try:
            run_sequence(excitation, problem.sequence.iterations, opts.seed, prior, progress, done, engine)
        except KeyboardInterrupt:
            err.print(f"interrupted: kept {len(finished)} finished iteration(s) in {target}")
            raise typer.Exit(130) from None
    return finished


@app.command()
@_user_errors
def optimize(
    config: Path = typer.Argument(..., help="Problem YAML file (see README 'Config reference')."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="HDF5 result file (overrides config 'output')."),
    iterations: Optional[int] = typer.Option(None, "--iterations", "-k", min=1, help="Sequential iterations (overrides sequence.iterations)."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Seed of the random starts (overrides optimizer.seed)."),
    workers: Optional[int] = typer.Option(None, "--workers", min=1, help="Local processes for the restarts (overrides optimizer.workers; default: the cores)."),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Dask scheduler address, e.g. tcp://host:8786 (overrides optimizer.scheduler)."),
) -> None:
    """Optimize Fourier trajectories minimizing cond of the stacked base regressor, sequentially.

    Writes the HDF5 result (rewritten after every finished iteration, so Ctrl-C keeps the finished
    ones), PNG plots beside it, and prints the condition-number table.
    """
    problem = load_problem(config)
    if iterations is not None:
        problem.sequence.iterations = iterations
    if seed is not None:
        problem.optimizer.seed = seed
    _override_engine(problem, workers, scheduler)
    target = output if output is not None else Path(problem.output)
    excitation = build_excitation(problem)
    with _engine(problem, excitation) as engine:
        finished = _optimize(problem, excitation, target, engine)
    out.print(_table(finished))
    plots = plot_result(target, excitation, finished)
    out.print(f"wrote {target} and {', '.join(str(p) for p in plots)}", highlight=False)


@app.command("compare-random")
@_user_errors
def compare_random(
    config: Path = typer.Argument(..., help="Problem YAML file."),
    optimized: Optional[Path] = typer.Option(None, "--optimized", help="Optimized result (HDF5) to compare with; computed when not given."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="HDF5 file of the random selection (default: <config output>_random.h5)."),
    pool: Optional[int] = typer.Option(None, "--pool", min=1, help="Feasible random candidates to draw (overrides random_baseline.pool_size)."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Seed of the random candidates (overrides random_baseline.seed)."),
    equal_effort: bool = typer.Option(False, "--equal-effort", help="Draw candidates for as long as the optimizer took, instead of a fixed pool."),
    workers: Optional[int] = typer.Option(None, "--workers", min=1, help="Local processes for restarts and draws (overrides optimizer.workers)."),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Dask scheduler address (overrides optimizer.scheduler)."),
) -> None:
    """The conventional baseline of the paper's ref. [16]: random feasible Fourier trajectories and
    greedy selection (Table II), beside the optimized trajectories (Table I) with the ratio per
    iteration and the wall time of each method."""
    problem = load_problem(config)
    _override_engine(problem, workers, scheduler)
    rcfg = problem.random_baseline
    if pool is not None:
        rcfg.pool_size = pool
    if seed is not None:
        rcfg.seed = seed
    base_target = Path(problem.output)
    target = output if output is not None else base_target.with_name(base_target.stem + "_random.h5")
    excitation = build_excitation(problem)
    with _engine(problem, excitation) as engine:
        if optimized is None:
            optimized = base_target.with_name(base_target.stem + "_optimized.h5")
            _optimize(problem, excitation, optimized, engine)
        optimized_table, optimized_time = read_table(optimized)
        count = len(optimized_table)
        size = None if equal_effort else max(rcfg.pool_size, count)
        with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.fields[status]}"),
                      TimeElapsedColumn(), console=err) as bar:
            task = bar.add_task("random candidates", total=size, status="")
            drawn = draw_pool(engine, size, rcfg.seed, optimized_time if equal_effort else None,
                              lambda kept, tried: bar.update(task, completed=kept, status=f"{kept} kept of {tried} drawn"))
    if len(drawn.alphas) < count:
        raise ExciteError(f"random_baseline: only {len(drawn.alphas)} feasible candidates of {drawn.drawn} drawn; "
                          f"{count} are needed (enlarge the pool or the time)")
    start = time.perf_counter()
    chosen, _ = greedy_selection(drawn.regressors, count)
    selection_time = time.perf_counter() - start
    stacked = np.zeros((0, excitation.base.count))
    results = []
    for k, index in enumerate(chosen, start=1):
        results.append(describe(excitation, k, drawn.alphas[index], stacked))
        stacked = np.vstack([stacked, results[-1].regressor])
    random_time = drawn.generation_time_s + selection_time
    write_result(target, excitation, results, rcfg.seed, {
        "method": "random_selection", "pool_size": len(drawn.alphas), "drawn": drawn.drawn,
        "generation_time_s": drawn.generation_time_s, "selection_time_s": selection_time,
    })
    random_table = read_table(target)[0]
    out.print(_comparison(random_table, optimized_table, random_time, optimized_time, len(drawn.alphas), drawn.drawn))
    sizes = sorted({s for s in (count, 10, 30, 100, 300, 1000, 3000, len(drawn.alphas)) if count <= s <= len(drawn.alphas)})
    convergence = Table(title="Random selection: best cond(C) against pool size")
    convergence.add_column("pool", justify="right")
    for k in range(1, count + 1):
        convergence.add_column(f"cond(C) at {k}", justify="right")
    for size_, conds in pool_convergence(drawn.regressors, count, sizes):
        convergence.add_row(str(size_), *[f"{c:.1f}" for c in conds])
    out.print(convergence)
    plot = plot_comparison(target.with_suffix("").with_name(target.stem + "_comparison.png"), random_table, optimized_table)
    out.print(f"wrote {target} and {plot}", highlight=False)


@app.command()
@_user_errors
def identify(
    config: Path = typer.Argument(..., help="Identification YAML: robot, data, preprocessing, identification (see README)."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="HDF5 result (overrides config 'output')."),
    physical_consistency: bool = typer.Option(False, "--physical-consistency", help="Also fit physically consistent standard parameters (identification.physical_consistency)."),
    urdf_out: Optional[Path] = typer.Option(None, "--urdf-out", help="Write the URDF with the identified inertias and friction (implies --physical-consistency)."),
) -> None:
    """Identify base parameters on measured data (Eq. 4), trace the residual to the effects the
    rigid-body model lacks, add them, and report the torque error before and after on held-out data;
    optionally fit physically consistent standard parameters and write them as a URDF."""
    problem = load_problem(config, IdentifyProblem)
    if physical_consistency or urdf_out is not None:
        problem = problem.model_copy(deep=True)
        problem.identification.physical_consistency = True
    target = output if output is not None else Path(problem.output)
    with err.status("preprocessing, fitting and selecting effects ..."):
        report, robot, base, regressor = run_identification(problem)
    sel = report.selection
    source = "preprocessing.cutoff" if problem.preprocessing.cutoff else "default: 10 × the 99 % power bandwidth of q"
    err.print(f"low-pass cut-off {report.cutoff:.3g} Hz ({source}); stored as cutoff_Hz", highlight=False)
    for name, rows in report.dropped:
        err.print(f"data.bad_rows: dropped {rows} unusable row(s) of {name}", highlight=False)
    table = Table(title=f"Validation torque error, rigid body only → with the chosen effects ({report.validation_samples} held-out instants)")
    consistent = report.relative_consistent
    for column in ("joint", "RMS τ [Nm]", "before [Nm]", "after [Nm]", "before [%]", "after [%]") + (("consistent [%]",) if consistent is not None else ()):
        table.add_column(column, justify="right")
    for j, name in enumerate(report.joints):
        table.add_row(name, f"{report.rms_torque[j]:.3f}", f"{report.rms_before[j]:.3f}", f"{report.rms_after[j]:.3f}",
                      f"{report.relative_before[j]:.1f}", f"{report.relative_after[j]:.1f}",
                      *((f"{consistent[j]:.1f}",) if consistent is not None else ()))
    table.caption = (f"mean: before {report.relative_before.mean():.1f} %, after {report.relative_after.mean():.1f} %"
                     + (f", physically consistent {consistent.mean():.1f} %" if consistent is not None else ""))
    out.print(table)
    effects = Table(title="Effects, in the order they were added (declared ones first)")
    for column in ("#", "effect", "joint", "coefficient", "value", "std"):
        effects.add_column(column, justify="right")
    order = {key: k + 1 for k, key in enumerate((e, report.joints[j]) for e, j in sel.effects)}
    for effect, coefficient, joint, value, std in effect_values(report):
        effects.add_row(str(order[(effect, joint)]), effect, joint, f"{coefficient} [{EFFECT_UNITS[coefficient]}]", f"{value:.5g}", f"{std:.2g}")
    out.print(effects)
    if sel.absorbed:
        out.print("not separately identifiable (in the span of the base parameters): "
                  + ", ".join(f"{e}:{report.joints[j]}" for e, j in sel.absorbed), highlight=False)
    params = Table(title="Identified base parameters")
    for column in ("base parameter", "value", "std"):
        params.add_column(column, justify="right")
    for name, value, std in zip(report.base_names, sel.fit.x, sel.fit.std):
        params.add_row(name, f"{value:.5g}", f"{std:.2g}")
    out.print(params)
    if report.consistent is not None:
        out.print(_bodies(report, robot))
    write_identification(target, report, robot, base, problem.source_text, regressor, problem.identification.method)
    if urdf_out is not None:
        deviation = write_identified_urdf(problem, report, robot, base, urdf_out)
        out.print(f"wrote {urdf_out}: pinocchio's RNEA on it matches the identified rigid-body torques to {deviation:.1e} Nm", highlight=False)
    plot = plot_identification(target.with_suffix("").with_name(target.stem + "_residuals.png"), report)
    out.print(f"wrote {target} and {plot}", highlight=False)


@app.command()
@_user_errors
def export(
    result: Path = typer.Argument(..., help="An optimize (or compare-random) HDF5 result."),
    iteration: Optional[int] = typer.Option(None, "--iteration", "-k", help="Iteration to export (default: the last)."),
    rate: float = typer.Option(1000.0, "--rate", help="Controller rate [Hz]."),
    fmt: ExportFormat = typer.Option("csv", "--format", help="File format."),
    periods: int = typer.Option(1, "--periods", help="Periods of the trajectory to play."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="File to write (default: beside the result)."),
) -> None:
    """Write a trajectory as a robot plays it: from the home posture at rest, P periods, back to rest,
    at the controller's rate, with the feed-forward torques; every constraint is re-checked."""
    exported = export_trajectory(result, iteration, rate, periods)
    target = output if output is not None else result.with_name(f"{result.stem}_iteration{exported.iteration}_{rate:g}Hz.{fmt.value}")
    write_export(target, exported, fmt.value)
    for name, start, duration in exported.segments:
        out.print(f"{name:>15}: {start:8.3f} s → {start + duration:8.3f} s", highlight=False)
    out.print(f"{exported.time.size} samples at {rate:g} Hz; every constraint holds: largest normalized violation "
              f"{exported.max_violation:+.2e} (≤ 0 satisfied), closest: {exported.worst}", highlight=False)
    out.print(f"wrote {target}", highlight=False)


@app.command()
@_user_errors
def validate(
    report: Path = typer.Argument(..., help="An identify report (HDF5)."),
    config: Path = typer.Argument(..., help="Identification YAML whose data.runs are the runs to score (roles are ignored)."),
) -> None:
    """Score an identified model on other runs: torque error per run and joint, with the report's
    preprocessing (cut-off), on data its fit and effect selection never saw."""
    problem = load_problem(config, IdentifyProblem)
    with err.status("preprocessing and predicting ..."):
        errors = validate_model(report, problem)
    table = Table(title=f"Validation of {report.name}: relative RMS torque error [%] per run")
    for column in ("run", "instants", *problem.robot.active_joints, "mean"):
        table.add_column(column, justify="right")
    for e in errors:
        table.add_row(e.name, str(e.instants), *[f"{x:.1f}" for x in e.relative], f"{e.relative.mean():.1f}")
    out.print(table)


@app.command()
@_user_errors
def simulate(
    result: Path = typer.Argument(..., help="An optimize (or compare-random) HDF5 result: its trajectories are simulated."),
    effects: Path = typer.Argument(..., help="Effects file (YAML): effects, noise, sample rate, jitter (see README)."),
    output_dir: Path = typer.Option(Path("results/simulated"), "--output-dir", "-o", help="Folder for the CSV runs."),
) -> None:
    """Make measured-like CSV runs (one per iteration) from a result's trajectories and the URDF model,
    with the effects and noise of the effects file, in the format `identify` reads."""
    sim = load_problem(effects, SimulationConfig)
    files = simulate_runs(result, sim, output_dir)
    out.print("wrote " + ", ".join(str(f) for f in files), highlight=False)


def _bodies(report, robot) -> Table:
    """Identified (physically consistent) bodies beside the URDF's, and the active constraints."""
    table = Table(title=f"Physically consistent bodies (identified / URDF), solver {report.consistent.status}")
    for column in ("body", "mass [kg]", "CoM [m]", "principal moments about the CoM [kg m²]", "λmin(J)"):
        table.add_column(column, justify="right")
    urdf = robot.urdf_parameters()
    for i, name in enumerate(robot.body_names):
        m, c, _, moments = body_properties(report.consistent.standard[10 * i: 10 * i + 10])
        um, uc, _, umoments = body_properties(urdf[10 * i: 10 * i + 10])
        vector = lambda v: " ".join(f"{x:+.3f}" for x in v)
        table.add_row(name, f"{m:.3f} / {um:.3f}", f"{vector(c)} / {vector(uc)}",
                      f"{' '.join(f'{x:.2e}' for x in moments)} / {' '.join(f'{x:.2e}' for x in umoments)}",
                      f"{report.consistent.min_eigenvalues[i]:.1e}")
    plain = [(name, body_properties(report.consistent.unconstrained[10 * i: 10 * i + 10])[0]) for i, name in enumerate(robot.body_names)
             if np.linalg.eigvalsh(pseudo_inertia(report.consistent.unconstrained[10 * i: 10 * i + 10]))[0] <= 0.0]
    table.caption = ("active: " + (", ".join(report.consistent.active) or "none")
                     + "\nplain least squares (same regularization) is not physical for: "
                     + (", ".join(f"{name} (mass {m:.3f} kg)" for name, m in plain) or "none"))
    return table


def _comparison(random_table, optimized_table, random_time: float, optimized_time: float, pool: int, drawn: int) -> Table:
    table = Table(title=f"Table II (random, {pool} feasible of {drawn} drawn) beside Table I (optimized)")
    for column in ("motion", "rand cond(C(i))", "rand cond(C)", "opt cond(C(i))", "opt cond(C)", "ratio"):
        table.add_column(column, justify="right")
    for r, o in zip(random_table, optimized_table):
        table.add_row(str(r["iteration"]), f"{r['cond_own']:.1f}", f"{r['cond_stacked']:.1f}", f"{o['cond_own']:.1f}",
                      f"{o['cond_stacked']:.1f}", f"{r['cond_stacked'] / o['cond_stacked']:.1f}")
    table.caption = f"wall time: random {random_time:.0f} s, optimized {optimized_time:.0f} s; ratio = random/optimized cond(C)"
    return table


@app.command("verify-gradient")
@_user_errors
def verify_gradient(
    config: Path = typer.Argument(..., help="Problem YAML file."),
    result: Optional[Path] = typer.Option(None, "--result", "-r", help="Also check at the last iteration's optimum of this HDF5 result."),
    step: float = typer.Option(1e-6, min=1e-12, help="Finite-difference step on each Fourier coefficient."),
    seed: int = typer.Option(0, help="Seed of the random feasible trajectory."),
    objective: Optional[list[str]] = typer.Option(None, "--objective", help=f"Criteria to check (repeatable; default all: {', '.join(OBJECTIVES)})."),
    tolerance: float = typer.Option(1e-6, help="Largest relative error against central differences that passes."),
) -> None:
    """Compare the analytic gradients of the criteria (Eq. 49) with finite differences: error and
    speed; the constraint Jacobians too. Exit status 1 when an error exceeds the tolerance."""
    objectives = objective or list(OBJECTIVES)
    for name in objectives:
        if name not in OBJECTIVES:
            raise ExciteError(f"--objective: '{name}' is not a criterion; expected one of {', '.join(OBJECTIVES)}")
    excitation = build_excitation(load_problem(config))
    alpha = excitation.limits.random_start(excitation.trajectory.n_coefficients, np.random.default_rng(seed), fill=0.7)
    points = [("random", None, alpha)] + ([_optimum(result, excitation)] if result is not None else [])
    table = Table(title="Analytic gradient vs finite differences")
    for column in ("point", "objective", "vars", "value", "err central", "err 1-sided", "analytic [s]", "FD 1-sided [s]", "ratio"):
        table.add_column(column, justify="right")
    errors = []
    for label, prior, a in points:
        for name in objectives:
            excitation.problem.optimizer.objective = name
            check = check_gradient(excitation.criterion(prior), a, step=step)
            errors.append(check.error_central)
            table.add_row(label, name, str(check.variables), f"{check.value:.4g}", f"{check.error_central:.2e}",
                          f"{check.error_forward:.2e}", f"{check.analytic_s:.4f}", f"{check.forward_s:.3f}",
                          f"{check.speedup:.0f}×")
    out.print(table)
    lively = excitation.limits.random_start(excitation.trajectory.n_coefficients, np.random.default_rng(seed), 0.9, excitation.home)
    jacobians = Table(title="Constraint Jacobians vs central differences (random trajectory at 90 % of the limits)")
    for column in ("constraint", "rows", "rel. error"):
        jacobians.add_column(column, justify="right")
    for c in excitation.constraints:
        errors.append(constraint_jacobian_error(c, lively))
        jacobians.add_row(c.name, str(c.evaluate(lively)[0].size), f"{errors[-1]:.2e}")
    out.print(jacobians)
    worst = max(errors)
    out.print(f"{'PASS' if worst <= tolerance else 'FAIL'}: largest relative error {worst:.2e} (tolerance {tolerance:.0e})")
    if worst > tolerance:
        raise typer.Exit(1)


def _optimum(path: Path, excitation: Excitation) -> tuple[str, np.ndarray, np.ndarray]:
    """The last iteration's label, C₀ (the earlier iterations' rows) and α, from a result file."""
    index, alpha = read_last_alpha(path)
    if alpha.shape != (excitation.robot.n_joints, excitation.trajectory.n_coefficients):
        raise ExciteError(f"--result: {path} was made for another problem (alpha shape {alpha.shape})")
    prior = read_prior(path, excitation.base)
    own_rows = excitation.cost_basis.time.size * excitation.robot.n_rows
    return f"optimum {index}", prior[:-own_rows], alpha
