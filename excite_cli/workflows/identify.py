"""``identify``: the identification, its report file, plots and the identified URDF."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional

from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.pipeline import run_identification, write_identified_urdf
from excite_cli.identification.reporting.report import Report
from excite_cli.identification.reporting.report_file import write_identification
from excite_cli.plots.identification import plot_identification, plot_ladder
from excite_cli.storage.paths import check_target, output_lock


@dataclass
class IdentifyRun:
    """``identify``: the report, the robot, the files written (report, plots) and the URDF round-trip
    deviation [Nm]."""

    report: Report
    robot: Robot
    target: Path
    plots: list[Path]
    urdf_deviation: Optional[float]


def run_identify(
    problem: IdentifyProblem, target: Path, urdf_out: Optional[Path] = None, force: bool = False
) -> IdentifyRun:
    """Identify (:func:`run_identification`), write the report (HDF5), the residual plot and, with
    ``urdf_out``, the identified URDF (of the physically consistent fit, which is then fitted whatever
    ``identification.fit`` says: a URDF needs physical bodies).

    Raises:
        ExciteError: bad paths or data (see :func:`run_identification`); another run writing
            ``target`` (:func:`output_lock`).
    """
    check_target(target, "output", force)
    plots = [target.with_name(target.stem + suffix) for suffix in ("_residuals.png", "_ladder.png")]
    if urdf_out is not None:
        check_target(urdf_out, "urdf_out", force)
        if Path(urdf_out).resolve() in {p.resolve() for p in [target, *plots]}:
            raise ExciteError(
                "urdf_out", f"{urdf_out} is also the report or one of its plots", urdf_out, "another path"
            )
    with output_lock(target, "output"):
        report, robot, base, regressor = run_identification(problem, consistent_beside=urdf_out is not None)
        write_identification(target, report, robot, base, problem, regressor)
        deviation = write_identified_urdf(problem, report, robot, base, urdf_out) if urdf_out is not None else None
        plots = [plot_identification(plots[0], report), plot_ladder(plots[1], report)]
    return IdentifyRun(report, robot, target, plots, deviation)
