"""``excite validate``: an identify report's model scored on the runs of an identification config."""

from __future__ import annotations

from pathlib import Path

from excite_cli.config_file import load_problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.validate import RunError, validate_model


def run_validate(report: Path, config: Path) -> tuple[IdentifyProblem, list[RunError]]:
    """The identification config at ``config`` and the relative RMS torque error of ``report``'s
    model on each of its runs (:func:`~excite_cli.identification.validate.validate_model`).

    Raises:
        ExciteError: a bad config, a report for another robot, bad data.
    """
    problem = load_problem(config, IdentifyProblem)
    return problem, validate_model(report, problem)
