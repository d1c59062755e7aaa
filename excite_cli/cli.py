"""Command line: parses arguments and calls the library; every command can be done from Python too."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Callable, Optional

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from excite_cli.config import load_problem
from excite_cli.errors import ExciteError
from excite_cli.criterion import ConditionNumber
from excite_cli.excitation import Excitation, build_excitation
from excite_cli.output import read_last_alpha, read_prior, write_result
from excite_cli.plots import plot_condition_numbers, plot_trajectories
from excite_cli.sequence import IterationResult, run_sequence
from excite_cli.verify import check_gradient

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Persistently exciting trajectories for robot dynamic identification (Ayusawa et al. 2017).",
)
out = Console()
err = Console(stderr=True)


def _user_errors(command: Callable) -> Callable:
    """Turn ExciteError into one line on stderr and exit status 2; Ctrl-C into status 130."""

    @functools.wraps(command)
    def wrapper(*args, **kwargs):
        try:
            return command(*args, **kwargs)
        except ExciteError as exc:
            err.print(f"[bold red]error:[/] {exc}", highlight=False, soft_wrap=True)
            raise typer.Exit(2) from None

    return wrapper


def _table(results: list[IterationResult]) -> Table:
    table = Table(title="Condition numbers (Table I)")
    for column in ("iter", "cond(C(i))", "cond(C)", "max viol.", "SQP its", "time [s]"):
        table.add_column(column, justify="right")
    for r in results:
        table.add_row(
            str(r.index), f"{r.cond_own:.1f}", f"{r.cond_stacked:.1f}", f"{r.max_violation:+.2e}",
            str(r.sqp_iterations), f"{r.wall_time_s:.1f}",
        )
    return table


@app.command()
@_user_errors
def optimize(
    config: Path = typer.Argument(..., help="Problem YAML file (see README 'Config reference')."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="HDF5 result file (overrides config 'output')."),
    iterations: Optional[int] = typer.Option(None, "--iterations", "-k", min=1, help="Sequential iterations (overrides sequence.iterations)."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Seed of the random starts (overrides optimizer.seed)."),
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
    target = output if output is not None else Path(problem.output)
    excitation = build_excitation(problem)
    prior = read_prior(problem.resolve(problem.sequence.prior), excitation.base) if problem.sequence.prior else None
    err.print(
        f"{len(excitation.robot.joint_names)} active joints, {excitation.base.count} base parameters, "
        f"{excitation.trajectory.n_coefficients * excitation.robot.n_joints} Fourier coefficients, "
        f"{0 if prior is None else prior.shape[0]} prior rows",
        highlight=False,
    )
    finished: list[IterationResult] = []

    def keep(result: IterationResult) -> None:
        finished.append(result)
        write_result(target, excitation, finished, problem.optimizer.seed)

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
            def hook(restart: int, it: int, value: float) -> None:
                c = np.exp(value) if opts.objective == "log_cond" else value
                bar.update(tasks[k], completed=restart * opts.max_iterations + it,
                           status=f"restart {restart + 1}/{opts.restarts} · cond {c:.1f}")
            return hook

        def done(result: IterationResult) -> None:
            keep(result)
            bar.update(tasks[result.index], completed=opts.restarts * opts.max_iterations,
                       status=f"cond(C) {result.cond_stacked:.1f}")

        try:
            run_sequence(excitation, problem.sequence.iterations, opts.seed, prior, progress, done)
        except KeyboardInterrupt:
            err.print(f"interrupted: kept {len(finished)} finished iteration(s) in {target}")
            raise typer.Exit(130) from None
    out.print(_table(finished))
    stem = target.with_suffix("")
    plots = [
        plot_trajectories(stem.with_name(stem.name + "_trajectories.png"), excitation.robot.joint_names, finished),
        plot_condition_numbers(stem.with_name(stem.name + "_cond.png"), finished),
    ]
    out.print(f"wrote {target} and {', '.join(str(p) for p in plots)}", highlight=False)


@app.command("verify-gradient")
@_user_errors
def verify_gradient(
    config: Path = typer.Argument(..., help="Problem YAML file."),
    result: Optional[Path] = typer.Option(None, "--result", "-r", help="Also check at the last iteration's optimum of this HDF5 result."),
    step: float = typer.Option(1e-6, min=1e-12, help="Finite-difference step on each Fourier coefficient."),
    seed: int = typer.Option(0, help="Seed of the random feasible trajectory."),
) -> None:
    """Compare the analytic gradient of cond(C) (Eq. 49) with finite differences: error and speed."""
    problem = load_problem(config)
    problem.optimizer.objective = "cond"
    excitation = build_excitation(problem)
    alpha = excitation.limits.random_start(excitation.trajectory.n_coefficients, np.random.default_rng(seed), fill=0.7)
    points = [("random", excitation.criterion(), alpha)]
    if result is not None:
        points.append(_optimum(result, excitation))
    table = Table(title="Analytic gradient vs finite differences (objective: cond)")
    for column in ("point", "vars", "cond", "err central", "err 1-sided", "analytic [s]", "FD 1-sided [s]", "ratio"):
        table.add_column(column, justify="right")
    for label, criterion, a in points:
        check = check_gradient(criterion, a, step=step)
        table.add_row(label, str(check.variables), f"{check.value:.2f}", f"{check.error_central:.2e}",
                      f"{check.error_forward:.2e}", f"{check.analytic_s:.4f}", f"{check.forward_s:.3f}",
                      f"{check.speedup:.0f}×")
    out.print(table)


def _optimum(path: Path, excitation: Excitation) -> tuple[str, ConditionNumber, np.ndarray]:
    """The last iteration's α of a result file and its criterion, C₀ = the earlier iterations."""
    index, alpha = read_last_alpha(path)
    if alpha.shape != (excitation.robot.n_joints, excitation.trajectory.n_coefficients):
        raise ExciteError(f"--result: {path} was made for another problem (alpha shape {alpha.shape})")
    prior = read_prior(path, excitation.base)
    own_rows = excitation.cost_basis.time.size * excitation.robot.n_rows
    return f"optimum {index}", excitation.criterion(prior[:-own_rows]), alpha
