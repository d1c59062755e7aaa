"""``identify``: the identification, its report file, plots and the identified model as URDF and MJCF."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.robot import Robot
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.errors import ExciteError
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.pipeline import run_identification, write_identified_urdf
from excite_cli.identification.reporting.mjcf_check import MujocoCheck, check_mjcf
from excite_cli.identification.reporting.mjcf_out import MjcfModel, write_mjcf
from excite_cli.identification.reporting.report import Report
from excite_cli.identification.reporting.report_file import write_identification
from excite_cli.identification.reporting.urdf_out import check_urdf_source
from excite_cli.plots.identification import plot_identification, plot_ladder
from excite_cli.storage.paths import check_target, output_lock


@dataclass
class IdentifyRun:
    """``identify``: the report, the robot and its base parameters, the files written (report, plots),
    the URDF (or None) and its round-trip deviation [Nm], the MJCF (or None) and MuJoCo's check of it."""

    report: Report
    robot: Robot
    base: BaseParameters
    target: Path
    plots: list[Path]
    urdf: Optional[Path] = None
    urdf_deviation: Optional[float] = None
    mjcf: Optional[MjcfModel] = None
    mujoco: Optional[MujocoCheck] = None


def _check_model_paths(target: Path, plots: list[Path], models: dict[str, Optional[Path]], force: bool) -> None:
    """Refuse a model output ({field: path}) that exists (without ``force``), cannot be written, or is
    the report, a plot or the other model."""
    taken = {p.resolve(): "the report or one of its plots" for p in [target, *plots]}
    for name, path in models.items():
        if path is None:
            continue
        check_target(path, name, force)
        if Path(path).resolve() in taken:
            raise ExciteError(name, f"{path} is also {taken[Path(path).resolve()]}", path, "another path")
        taken[Path(path).resolve()] = "the other model file"


def write_identified_mjcf(
    problem: IdentifyProblem, report: Report, robot: Robot, base: BaseParameters, target: Path
) -> tuple[MjcfModel, MujocoCheck]:
    """Write the MJCF of the physically consistent fit (:func:`write_mjcf`) and check it with MuJoCo
    (:func:`check_mjcf`).

    Raises:
        ExciteError: no consistent fit in ``report``; MuJoCo missing, refusing or failing to load the model.
    """
    if report.consistent is None:
        raise ExciteError("mjcf_out", "needs the physically consistent fit (identification.fit)")
    source, package_dirs = resolve_urdf(problem.robot, problem.folder)
    effects = [(t, c, v) for t, c, v, _ in report.effect_values(consistent=True)]
    locked = dict(problem.robot.locked_joints)
    model = write_mjcf(source, package_dirs, robot, locked, report.consistent.standard, effects, target)
    return model, check_mjcf(problem, report, robot, base, model)


def run_identify(
    problem: IdentifyProblem,
    target: Path,
    urdf_out: Optional[Path] = None,
    force: bool = False,
    mjcf_out: Optional[Path] = None,
    say: Optional[Callable[[str], None]] = None,
) -> IdentifyRun:
    """Identify (:func:`run_identification`, ``say`` told what is under way), write the report (HDF5),
    the residual plots and, with ``urdf_out`` or ``mjcf_out``, the identified URDF or MJCF (of the
    physically consistent fit, which is then fitted whatever ``identification.fit`` says: a model file
    needs physical bodies); the MJCF is written and checked by MuJoCo before the report, which records
    the check.

    Raises:
        ExciteError: bad paths or data (see :func:`run_identification`); another run writing
            ``target`` (:func:`output_lock`); see :func:`write_identified_mjcf`.
    """
    check_target(target, "output", force)
    plots = [target.with_name(target.stem + suffix) for suffix in ("_residuals.png", "_ladder.png")]
    for figure in plots:  # written over only where excite wrote them
        check_target(figure, "output", force=True)
    _check_model_paths(target, plots, {"urdf_out": urdf_out, "mjcf_out": mjcf_out}, force)
    if urdf_out is not None:  # before the fit, not after it
        check_urdf_source(resolve_urdf(problem.robot, problem.folder)[0])
    with output_lock(target, "output"):
        report, robot, base, rows = run_identification(problem, urdf_out is not None or mjcf_out is not None, say)
        run = IdentifyRun(report, robot, base, target, plots, urdf_out)
        if mjcf_out is not None:
            run.mjcf, run.mujoco = write_identified_mjcf(problem, report, robot, base, mjcf_out)
        write_identification(target, report, robot, base, problem, rows, run.mjcf, run.mujoco)
        if urdf_out is not None:
            run.urdf_deviation = write_identified_urdf(problem, report, robot, base, urdf_out)
        run.plots = [plot_identification(plots[0], report), plot_ladder(plots[1], report)]
    return run
