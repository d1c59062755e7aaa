"""The files a problem names that an earlier run wrote (``effects.model``, ``sequence.prior``), each
resolved and opened once per command and handed on as values: the design takes its model and the
weighing of measured rows from them, the sequence its prior rows C₀."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from excite_cli.config import resolve_path
from excite_cli.stored.prior import PriorFile, read_prior_file
from excite_cli.stored.report import StoredReport, identify_report, read_identify_report


@dataclass(frozen=True)
class StoredInputs:
    """What ``effects.model`` and ``sequence.prior`` hold.

    Attributes:
        model: the identify report of ``effects.model``, or None (none named); model_path: its file.
        prior: the file of ``sequence.prior`` (its rows, and its report when it is one), or None.
    """

    model: StoredReport | None = None
    model_path: Path | None = None
    prior: PriorFile | None = None


def read_inputs(model: str | None, prior: str | None, folder: Path | None) -> StoredInputs:
    """The files a problem names, each opened once: ``effects.model``'s report alone (not its rows),
    ``sequence.prior``'s rows and report; one file named by both is read once, as the prior (its
    errors named under ``sequence.prior``).

    Args:
        model: ``effects.model``; prior: ``sequence.prior``; each relative to ``folder``, or None.

    Raises:
        FileNotFound, ExciteError: a file missing or unreadable; ``effects.model`` not an identify
            report (:func:`~excite_cli.stored.report.identify_report`).
    """
    model_path = resolve_path(model, folder) if model else None
    prior_path = resolve_path(prior, folder) if prior else None
    stored = None if prior_path is None else read_prior_file(prior_path)
    if model_path is None:
        report = None
    elif stored is not None and prior_path.resolve() == model_path.resolve():
        report = identify_report(stored.report, model_path, "effects.model")
    else:
        report = read_identify_report(model_path, "effects.model")
    return StoredInputs(report, model_path, stored)
