"""``excite validate``: an identified model (an ``identify`` report) scored on other runs, ones that
neither its fit nor its effect selection saw.

The runs of the config are read and preprocessed as ``identify`` does, with the report's cut-off,
and all of their instants are predicted by the report's model (base parameters, then its effects
with their coefficients and shape velocities; the load-dependent Coulomb column from the report's
rigid-body parameters, as in the fit; offsets the mean of the fitted runs' offsets, since a new
run's own offset is unknown). Errors per run and joint: RMS [Nm] and RMS relative to the measured
torque's RMS [%].
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.robot import load_robot
from excite_cli.errors import ExciteError
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import build_datasets
from excite_cli.identification.fitting.least_squares import predict, torque_errors
from excite_cli.identification.measured.gaps import split_at_gaps
from excite_cli.identification.measured.measurements import load_run
from excite_cli.identification.measured.payload import payload_parameters
from excite_cli.identification.measured.preprocessing import preprocess
from excite_cli.stored.report import read_identify_report


@dataclass(frozen=True)
class RunError:
    """One run's validation error: ``name``, ``rms`` (n,) [Nm], ``relative`` (n,) [%], ``instants``."""

    name: str
    rms: np.ndarray
    relative: np.ndarray
    instants: int


def validate_model(report: Path, problem: IdentifyProblem) -> list[RunError]:
    """Score the model of ``report`` on every run of ``problem`` (their roles are ignored; a run's
    offset is the mean of the report's fitted runs' offsets, a run's known payload is taken out).

    Raises:
        ExciteError: a report for another robot (joints or base parameters differ), bad data or
            config (as ``identify``).
    """
    model = read_identify_report(report, "report")
    robot = load_robot(problem.robot, problem.folder, joint_rows_only=True, physical=False)
    base = compute_base_parameters(robot)
    if model.joints != robot.joint_names:
        raise ExciteError("report", f"{report} was identified for other joints than the config's robot")
    order = base.column_order(model.base_names, "report", report)  # the same base, maybe in another order
    model = replace(model, base_names=base.names, base=model.base[order], rigid=model.rigid[order])
    terms = [
        Term(e, int(np.flatnonzero(c)[0]), s, c) if c else Term(e, robot.joint_names.index(j), s)
        for e, j, s, c in model.terms
    ]
    needed = terms + [Term("coulomb", j) for j in range(robot.n_joints)]
    errors = []
    for k, run in enumerate(problem.data.runs):
        pieces = split_at_gaps(  # a gap is never interpolated across, as in identify
            load_run(run.model_copy(update={"role": "validation"}), problem.data, robot.joint_names, problem.folder)
        )
        samples = [preprocess(piece, problem.preprocessing, model.cutoff) for piece in pieces]
        payload = [payload_parameters(robot, run.payload, f"data.runs[{k}].payload") if run.payload else None]
        payload *= len(samples)
        _, data, _ = build_datasets(
            robot,
            base,
            samples,
            needed,
            model.coulomb_velocity,
            problem.data.validation_blocks,
            payload,
            split=False,
            offset_runs=model.offset_runs,
            q_range=model.q_range,
        )
        data = data.with_load_columns(model.rigid, [t for t in terms if t.kind.two_stage])
        predicted = predict(data, np.concatenate([model.base, model.coefficients]), terms)
        rms, _, relative = torque_errors(data.tau.reshape(-1, data.n), predicted)
        errors.append(RunError(run.label, rms, relative, data.time.size))
    return errors
