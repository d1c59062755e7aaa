"""Command line: parses options, calls one library function per command, prints what it returns."""

from pathlib import Path
from typing import Optional

import typer
from rich.markup import escape

from excite_cli import console, workflows
from excite_cli.console.app import FORCE, JOINTS, MODEL, PRIOR, RUNS, SCHEDULER, WORKERS, app, command, err, say
from excite_cli.console.progress import Bars, Stages
from excite_cli.criteria import NAMES as OBJECTIVES
from excite_cli.storage.formats import FORMATS


def _load(path: Path, overrides: Optional[dict] = None, kind: str = "optimize"):
    """The ``kind`` config at ``path`` with the options' ``overrides`` (:func:`load_config`), a path given
    on the command line made absolute."""
    from excite_cli.config_file import ConfigKind, load_config  # here, not at start-up

    given = {field: str(v.resolve()) if isinstance(v, Path) else v for field, v in (overrides or {}).items()}
    return load_config(path, given, ConfigKind(kind))


@app.callback()
def main(version: bool = console.app.VERSION, quiet: bool = console.app.QUIET) -> None:
    """Persistently exciting trajectories for robot dynamic identification (Ayusawa et al. 2017)."""


@command()
def optimize(
    config: Path = typer.Argument(..., help="Problem YAML file (see docs/config-reference.md)."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="HDF5 result file (overrides config 'output')."),
    iterations: Optional[int] = typer.Option(None, "--iterations", "-k", help="Iterations (sequence.iterations)."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Seed of the random starts (optimizer.seed)."),
    workers: Optional[int] = WORKERS,
    scheduler: Optional[str] = SCHEDULER,
    prior: Optional[Path] = PRIOR,
    model: Optional[Path] = MODEL,
    force: bool = FORCE,
    resume: bool = typer.Option(False, "--resume", help="Continue the iterations already in the output file."),
    dry_run: bool = typer.Option(False, "--dry-run", help="Build the problem and say what would run (as `check`)."),
) -> None:
    """Optimize exciting Fourier trajectories by optimizer.objective (default A-optimality; log_cond: the paper's)."""
    overrides = {"sequence.iterations": iterations, "optimizer.seed": seed, "optimizer.workers": workers}
    problem = _load(
        config, overrides | {"optimizer.scheduler": scheduler, "sequence.prior": prior, "effects.model": model}
    )
    if dry_run:
        return say(console.plans.plan(workflows.plan_optimize(problem)))
    with Bars(console.app.busy) as bars:
        run = workflows.run_optimize(
            problem, output or Path(problem.output), force, resume, *bars.iterations(problem.optimizer)
        )
    say(
        console.tables.iterations(run.results, problem.optimizer, run.improved),
        run.designed_for,
        f"wrote {run.target} and {', '.join(str(p) for p in run.plots)}",
    )
    if run.warning:
        err.print(f"[bold yellow]warning:[/] {escape(run.warning)}", highlight=False, soft_wrap=True)
        raise typer.Exit(1)


@command()
def init(
    urdf: str = console.app.ROBOT_FILE,
    joints: Optional[list[str]] = JOINTS,
    kind: str = console.app.KIND,
    runs: Optional[list[str]] = RUNS,
    output: Optional[Path] = console.app.CONFIG_OUTPUT,
    force: bool = FORCE,
    collision: bool = console.app.COLLISION,
    package_dir: Optional[list[str]] = console.app.PACKAGE_DIRS,
    stand: Optional[bool] = console.app.STAND,
    srdf: Optional[Path] = console.app.SRDF,
    posture: Optional[str] = console.app.POSTURE,
    soles: Optional[list[str]] = console.app.SOLES,
    budget: float = console.app.BUDGET,
    torque_from: Optional[str] = console.app.TORQUE_FROM,
) -> None:
    """A starting config for your robot from its URDF or MJCF: joints, limits, capsules, floor, stance, home, sizes."""
    with console.app.busy.status("finding the stance, fitting capsules and searching postures ..."):
        stance = {"stand": stand, "srdf": srdf, "posture": posture, "soles": soles}
        run = workflows.run_init(
            urdf, output, joints, kind, force, runs, collision, package_dir, stance, 60 * budget, torque_from
        )
    say(console.plans.initialized(run))


@command()
def schema(
    output_dir: Path = typer.Option(Path("schema"), "--output-dir", "-o", help="Folder for the schema files."),
    force: bool = FORCE,
) -> None:
    """JSON Schema of every config kind (optimize, identify, effects), for editors and the config reference."""
    say("wrote " + ", ".join(str(p) for p in workflows.run_schema(output_dir, force)))


@command()
def check(
    config: Path = typer.Argument(..., help="Optimize or identify YAML file."),
    iterations: Optional[int] = typer.Option(None, "--iterations", "-k", help="Sequential iterations."),
    workers: Optional[int] = WORKERS,
) -> None:
    """What `optimize` or `identify` would run, not running it (joints, base, constraints, runs); exit 2 if refused."""
    overrides = {"sequence.iterations": iterations, "optimizer.workers": workers}
    with console.app.busy.status("building the problem ..."):
        plan = workflows.plan_check(config, overrides)
    say(console.identification.plan(plan) if hasattr(plan, "runs") else console.plans.plan(plan))


@command("compare-random")
def compare_random(
    config: Path = typer.Argument(..., help="Problem YAML file."),
    optimized: Optional[Path] = console.app.OPTIMIZED,
    output: Optional[Path] = console.app.RANDOM_OUTPUT,
    pool: Optional[int] = typer.Option(None, "--pool", help="Feasible random candidates (random_baseline.pool_size)."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Seed of the candidates (random_baseline.seed)."),
    equal_effort: bool = typer.Option(False, "--equal-effort", help="Draw for as long as the optimizer took."),
    workers: Optional[int] = WORKERS,
    scheduler: Optional[str] = SCHEDULER,
    force: bool = FORCE,
) -> None:
    """The conventional baseline (ref. [16]): random feasible trajectories, greedy selection, beside the optimum."""
    overrides = {"random_baseline.pool_size": pool, "random_baseline.seed": seed, "optimizer.workers": workers}
    problem = _load(config, overrides | {"optimizer.scheduler": scheduler})
    with Bars(console.app.busy) as bars:
        progress = bars.iterations(problem.optimizer)[0] if optimized is None else None
        draws = bars.draws(None if equal_effort else problem.random_baseline.pool_size)
        comparison = workflows.run_compare_random(problem, optimized, output, equal_effort, force, progress, draws)
    say(console.tables.comparison(comparison), f"wrote {comparison.target} and {comparison.plot}")


@command("verify-gradient")
def verify_gradient(
    config: Path = typer.Argument(..., help="Problem YAML file."),
    result: Optional[Path] = console.app.CHECKED_RESULT,
    step: float = typer.Option(1e-6, help="Finite-difference step (rad)."),
    seed: int = typer.Option(0, help="Seed of the random α."),
    objective: Optional[list[str]] = console.app.OBJECTIVE,
    tolerance: float = typer.Option(1e-6, help="Largest relative error against central differences that passes."),
) -> None:
    """Analytic gradients (Eq. 49) and constraint Jacobians against finite differences; exit 1 above the tolerance."""
    verification = workflows.run_verify(_load(config), result, objective or OBJECTIVES, step, seed, tolerance)
    say(console.tables.verification(verification, tolerance))
    raise typer.Exit(int(verification.worst > tolerance))


@command()
def identify(
    config: Path = typer.Argument(..., help="Identification YAML: robot, data, preprocessing, identification."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="HDF5 report (overrides config 'output')."),
    fit: Optional[str] = console.app.FIT,
    urdf_out: Optional[Path] = typer.Option(None, "--urdf-out", help="Write the identified URDF (consistent fit)."),
    mjcf_out: Optional[Path] = typer.Option(None, "--mjcf-out", help="Write the identified MJCF, checked by MuJoCo."),
    force: bool = FORCE,
) -> None:
    """Identify base parameters (Eq. 4), trace the residual to missing effects, report the error before/after."""
    problem = _load(config, {"identification.fit": fit}, "identify")
    with Stages(console.app.busy, "reading the runs ...") as stages:
        run = workflows.run_identify(problem, output or Path(problem.output), urdf_out, force, mjcf_out, stages.say)
    say(console.identification.preprocessing_notes(run.report), console=err)
    say(
        console.identification.identification(run.report),
        [console.bodies.consistent_bodies(run.report.consistent, run.robot)] if run.report.consistent else [],
        [console.model_files.urdf_written(run)] if urdf_out else [],
        console.model_files.mjcf_written(run) if mjcf_out else [],
        f"wrote {run.target} and {', '.join(str(p) for p in run.plots)}",
    )


@command()
def export(
    result: Path = typer.Argument(..., help="An optimize (or compare-random) HDF5 result."),
    iteration: Optional[int] = typer.Option(None, "--iteration", "-k", help="Iteration (default: the last)."),
    rate: float = typer.Option(1000.0, "--rate", help="Controller rate (Hz)."),
    periods: int = typer.Option(1, "--periods", help="Periods to play."),
    fmt: str = typer.Option("csv", "--format", help=f"File format: {' or '.join(FORMATS)}."),
    speed: float = typer.Option(1.0, "--speed", help="Times the optimized speed (0.5: half as fast)."),
    effort: bool = console.app.EFFORT,
    force: bool = FORCE,
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="File to write (default: beside the result)."),
    approach: Optional[float] = console.app.APPROACH,
    joint_names: Optional[str] = console.app.JOINT_NAMES,
) -> None:
    """Write a trajectory as a robot plays it: home → P periods → home, at the controller's rate, with torques."""
    exported, target = workflows.run_export(
        result, iteration, rate, periods, fmt, output, force, speed, effort, approach, joint_names
    )
    say(console.export_lines.export_lines(exported, rate, target, fmt, effort))


@command()
def rehearse(
    result: Path = console.app.RESULT,
    iteration: Optional[int] = console.app.EVERY_ITERATION,
    speed: float = console.app.SPEED,
    mjcf: Optional[Path] = console.app.MJCF,
    record: Optional[Path] = console.app.RECORD,
    plot: Optional[Path] = console.app.PLOT,
    controller: Optional[Path] = console.app.CONTROLLER,
    joints: Optional[str] = console.app.MJCF_JOINTS,
    effects: Optional[Path] = console.app.NOISE,
    force: bool = FORCE,
) -> None:
    """The export played in MuJoCo on the lab's controller before the robot moves; exit 1 if it falls, passes a
    limit or touches something."""
    noise = _load(effects, kind="effects") if effects else None
    with console.app.busy.status("playing in MuJoCo ...") as status:
        done = workflows.run_rehearse(
            result, iteration, speed, mjcf, record, plot, force, status.update, controller, joints, noise
        )
    say(console.rehearsal.rehearsal(done))
    raise typer.Exit(int(done.failed))


@command()
def view(
    result: Path = typer.Argument(..., help="An optimize (or compare-random) HDF5 result."),
    iteration: Optional[int] = typer.Option(None, "--iteration", "-k", help="Iteration (default: the last)."),
    rate: float = typer.Option(30.0, "--rate", help="Frames per second."),
    force: bool = FORCE,
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="HTML file (default: beside the result)."),
) -> None:
    """The motion as the robot would play it, in 3D, in one HTML file any browser opens (no server)."""
    say(f"wrote {workflows.run_view(result, iteration, output, rate, force)}")


@command()
def validate(
    report: Path = typer.Argument(..., help="An identify report (HDF5)."),
    config: Path = typer.Argument(..., help="Identification YAML whose data.runs are scored (roles ignored)."),
) -> None:
    """Score an identified model on other runs: torque error per run and joint, on data its fit never saw."""
    with console.app.busy.status("preprocessing and predicting ..."):
        problem, errors = workflows.run_validate(report, config)
    say(console.identification.validation(report.name, problem.robot.active_joints, errors))


@command()
def simulate(
    result: Path = typer.Argument(..., help="An optimize (or compare-random) result: its trajectories are simulated."),
    effects: Path = typer.Argument(..., help="Effects file (YAML): effects, noise, sample rate, jitter."),
    output_dir: Path = typer.Option(Path("results/simulated"), "--output-dir", "-o", help="Folder for the CSV runs."),
    force: bool = FORCE,
) -> None:
    """Measured-like CSV runs (one per iteration) of a result, with the effects and noise of an effects file."""
    files = workflows.simulate_runs(result, _load(effects, kind="effects"), output_dir, force=force)
    say("wrote " + ", ".join(str(f) for f in files))
