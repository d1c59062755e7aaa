"""The command line's frame: the typer app, its consoles, the options several commands share and the
guard every command runs in (one line and exit 2 for bad input, what was kept on Ctrl-C or SIGTERM)."""

import functools
from importlib import metadata
from typing import Callable, Optional

import typer
from rich.console import Console
from rich.markup import escape

from excite_cli.console.errors import printed_warnings, spellings, word
from excite_cli.console.progress import wide_console
from excite_cli.criteria import NAMES
from excite_cli.errors import ExciteError, Interrupted, Terminated, exit_status, sigterm_as_interrupt

app = typer.Typer(no_args_is_help=True)
#: Results (stdout), errors and warnings (stderr), and what is under way: spinners, bars and the
#: progress lines of a run without a terminal (stderr). ``--quiet`` silences ``out`` and ``busy``.
out, err, busy = wide_console(), wide_console(stderr=True), wide_console(stderr=True)


def _quiet(value: bool) -> bool:
    out.quiet = busy.quiet = value
    return value


def _version(show: bool) -> None:
    if show:
        out.print(f"excite {metadata.version('excite')}")
        raise typer.Exit()


VERSION = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version.")
QUIET = typer.Option(
    False, "--quiet", "-q", callback=_quiet, help="Print only errors, warnings and nothing under way (for scripts)."
)
FORCE = typer.Option(False, "--force", help="Replace existing output files.")
WORKERS = typer.Option(
    None, "--workers", help="Local processes for restarts and draws (optimizer.workers; default: the cores)."
)
SCHEDULER = typer.Option(None, "--scheduler", help="Dask scheduler, e.g. tcp://host:8786 (optimizer.scheduler).")
PRIOR = typer.Option(None, "--prior", help="Earlier result or identify report stacked first (sequence.prior).")
MODEL = typer.Option(None, "--model", help="Identify report whose effects to design for too (effects.model).")
JOINTS = typer.Option(
    None, "--joints", help="Active joints, repeatable or comma-separated (default: the arm's revolute joints)."
)
JOINT_NAMES = typer.Option(
    None, "--joint-names", help="Joints as the controller names them: robot=controller pairs, or a YAML map file."
)
APPROACH = typer.Option(
    None, "--approach", help="Seconds a ROS 2 trajectory gives to reach home first (default: from anywhere)."
)
EFFORT = typer.Option(
    False,
    "--effort",
    help="ros2/rosbag2: the feed-forward torque (gravity included) as the points' effort, for an effort-controlled "
    "joint_trajectory_controller (ros2_controllers 4.22 on, Jazzy); others refuse any effort.",
)
RUNS = typer.Option(None, "--runs", help="identify: measured runs (CSV, NPZ, MAT, HDF5, ROS bag), repeatable.")
ROBOT_FILE = typer.Argument(
    ..., help="URDF or MJCF file, or an example-robot-data path (ur_description/urdf/ur3_robot.urdf)."
)
PACKAGE_DIRS = typer.Option(
    None, "--package-dir", help="Folder holding the packages of package:// meshes (robot.package_dirs), repeatable."
)
COLLISION = typer.Option(
    True,
    "--collision/--no-collision",
    help="Fit capsules, a mounting plane or the floor and find soles in the collision geometry.",
)
OPTIMIZED = typer.Option(None, "--optimized", help="Optimized result to compare with; computed when not given.")
RANDOM_OUTPUT = typer.Option(None, "--output", "-o", help="Random selection HDF5 (default: <output>_random.h5).")
CHECKED_RESULT = typer.Option(None, "--result", "-r", help="Also check at the last optimum of this result.")
KIND = typer.Option("optimize", "--kind", help="Config kind: optimize or identify.")
CONFIG_OUTPUT = typer.Option(None, "--output", "-o", help="Config file (default: <file name>.yaml).")
STAND = typer.Option(
    None,
    "--stand/--no-stand",
    help="A standing problem (floating base on its soles, the arms moving) or a fixed base; default: standing "
    "where legs ending in soles and an arm are found.",
)
SRDF = typer.Option(None, "--srdf", help="The SRDF whose group state the robot stands in (default: the one beside it).")
POSTURE = typer.Option(
    None,
    "--posture",
    help="The named state to stand in (default: half_sitting, else standing*, else home; else searched).",
)
TORQUE_FROM = typer.Option(
    None, "--torque-from", help="Where the torques come from: sensor, current or unknown (the noise: section)."
)
SOLES = typer.Option(None, "--soles", help="The links that touch the floor, comma-separated (default: found).")
OBJECTIVE = typer.Option(None, "--objective", help=f"Criteria (repeatable; default all: {', '.join(NAMES)}).")
FIT = typer.Option(
    None, "--fit", help="auto (the cross-validation's choice), least_squares or consistent (identification.fit)."
)
RESULT = typer.Argument(..., help="An optimize (or compare-random) HDF5 result.")
EVERY_ITERATION = typer.Option(None, "--iteration", "-k", help="Iteration (default: every one).")
SPEED = typer.Option(1.0, "--speed", help="Times the optimized speed, as export plays it.")
MJCF = typer.Option(None, "--mjcf", help="The lab's MuJoCo model of the robot (default: the robot's file).")
RECORD = typer.Option(None, "--record", help="Folder for each played run as a recording identify reads.")
NOISE = typer.Option(None, "--effects", help="An effects file whose torque and position noise --record adds.")
PLOT = typer.Option(None, "--plot", help="PNG file (default: <result>_rehearsal.png beside it).")
MJCF_JOINTS = typer.Option(
    None, "--joint-names", help="Joints as the MJCF names them: robot=mjcf pairs, or a YAML map file."
)
CONTROLLER = typer.Option(None, "--config", help="A config whose rehearsal section replaces the result's.")
BUDGET = typer.Option(
    5.0, "--budget", help="Minutes the whole optimization may take (check's estimate): the optimizer's sizes fit it."
)


#: One command line per command that its ``--help`` shows as the example, run as written from the
#: repository's folder (a test runs each).
EXAMPLES = {
    "init": "excite init ur_description/urdf/ur10_robot.urdf --output ur10.yaml",
    "check": "excite check configs/panda.yaml",
    "schema": "excite schema --output-dir schema",
    "verify-gradient": "excite verify-gradient configs/smoke.yaml --objective log_det",
}


def command(name: Optional[str] = None) -> Callable:
    """A command of ``app``: ExciteError → one line, exit 2 (no traceback; 1 for a run that found no
    solution, :class:`~excite_cli.errors.NoSolution`); Ctrl-C or SIGTERM → what was kept, exit 130 or 143."""

    def register(function: Callable) -> Callable:
        @functools.wraps(function)
        def guarded(*args, **kwargs):
            try:
                with sigterm_as_interrupt(), printed_warnings(err):
                    return function(*args, **kwargs)
            except ExciteError as exc:
                line = word(exc, spellings(function, kwargs), kwargs.get("config") or kwargs.get("effects"))
                err.print(f"[bold red]error:[/] {escape(line)}", highlight=False, soft_wrap=True)
                raise typer.Exit(exc.status) from None
            except Interrupted as exc:
                err.print(str(exc), highlight=False, soft_wrap=True)
                raise typer.Exit(exc.status) from None
            except KeyboardInterrupt as exc:
                err.print("terminated" if isinstance(exc, Terminated) else "interrupted", highlight=False)
                raise typer.Exit(exit_status(exc)) from None

        example = EXAMPLES.get(name or function.__name__.replace("_", "-"))
        return app.command(name, epilog=f"Example: {example}" if example else None)(guarded)

    return register


def say(*items, console: Console = out) -> None:
    """Print tables and lines (as written, not rich markup), flattening lists."""
    for item in items:
        for part in item if isinstance(item, list) else [item]:
            console.print(escape(part) if isinstance(part, str) else part, highlight=False)
