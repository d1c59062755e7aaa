"""What ``identify`` prints of its search for effects: each step of the kept search with its gain and
the best moves it did not take, and the outcome of every start."""

from __future__ import annotations

import numpy as np
from rich.table import Table

from excite_cli.console.tables import titled_table
from excite_cli.identification.choice.admission import FAMILY_FOLDS, Admission
from excite_cli.identification.choice.search_record import MOVE_SIGNS, Step
from excite_cli.identification.reporting.report import Report


def search(report: Report, runners_up: int = 2) -> list[Table | str]:
    """Each step of the kept search with its gain and the best moves it did not take (every move
    tried is in the HDF5 report), and the outcome of every start."""
    sel = report.selection
    kept = sel.searches[sel.chosen]
    paired = sel.admission is Admission.PAIRED
    rows = []
    for k, step in enumerate(sel.steps, start=1):
        others = sorted(((v, m, t) for m, t, v in step.tried if (m, t) != (step.move, step.term)), key=lambda o: o[0])[
            :runners_up
        ]
        by_estimate = not np.isnan(step.clear_of_zero)  # judged by the estimate, not the folds
        rows.append(
            (
                str(k),
                step.label(report.joints) + (f" (estimate {step.clear_of_zero:.1f} std from 0)" if by_estimate else ""),
                f"{step.gain:.1f}",
                *(["—" if by_estimate else _folds(step)] if paired else []),
                "—" if by_estimate else str(len(step.tried)),
                "; ".join(f"{MOVE_SIGNS[m]} {t.label(report.joints)} {step.gain_of(v):.1f}" for v, m, t in others),
            )
        )
    steps = titled_table(
        f"Selection steps from the start '{kept.start}' (gain: cut of the cross-validated error [%]"
        + (
            "; folds: the mean gain over the folds and the margin of the paired test it passed, "
            f"from {FAMILY_FOLDS} folds on "
            "and in brackets the margin of the moves tested together, some move's gain above its own)"
            if paired
            else ")"
        ),
        ("step", "move", "gain [%]", *(["folds [%]"] if paired else []), "tried", f"next best {runners_up} [gain %]"),
        rows,
        "kept at its start: scored with the fits, the start wins (see the models compared)"
        if sel.at_start
        else f"stopped: {kept.stop}"
        + (f"\nrefused at the last step: {kept.refused.label(report.joints)}" if kept.refused else ""),
    )
    starts = "; ".join(
        f"{s.start}: {s.cv_error:.2f} % with {len(s.terms)} effects" + (" (kept)" if k == sel.chosen else "")
        for k, s in enumerate(sel.searches)
    )
    alone = sel.admission is Admission.PAIRED and sel.folds < FAMILY_FOLDS
    return [
        steps,
        f"searches (cross-validated error at their end): {starts}",
        f"effects admitted by: {sel.admission} ({sel.folds} folds by {sel.folds_by})"
        + (
            f"; with {sel.folds} folds each move is tested alone, and terms the data do not hold enter more often "
            f"than from {FAMILY_FOLDS} distinct recordings on, which test the moves of a step together"
            if alone
            else ""
        ),
    ]


def _folds(step: Step) -> str:
    """A step's mean gain over the folds > its margin, and its margin in the family-wise test if any."""
    family = "" if np.isnan(step.family_margin) else f" ({step.family_margin:.1f})"
    return f"{step.fold_gain:.1f} > {step.fold_margin:.1f}{family}"
