"""What ``identify`` and ``validate`` print: rich tables built from the identify report."""

from __future__ import annotations

from typing import Sequence

import numpy as np
from rich.table import Table

from excite_cli.console.effect_search import search
from excite_cli.console.noise_levels import noise_table
from excite_cli.console.tables import titled_table
from excite_cli.identification.choice.admission import Admission
from excite_cli.identification.reporting.report import Report
from excite_cli.identification.validate import RunError
from excite_cli.workflows.check_identify import IdentifyPlan


def validation(name: str, joints: Sequence[str], errors: Sequence[RunError]) -> Table:
    """Relative RMS torque error per run and joint of ``validate``."""
    return titled_table(
        f"Validation of {name}: relative RMS torque error [%] per run",
        ("run", "instants", *joints, "mean"),
        [(e.name, str(e.instants), *[f"{x:.1f}" for x in e.relative], f"{e.relative.mean():.1f}") for e in errors],
    )


def plan(p: IdentifyPlan) -> list[Table | str]:
    """What ``check`` found in an identify config: the robot, the runs as read, what would be fitted."""
    cfg = p.problem.identification
    rows = [
        (
            r.label,
            r.role,
            str(r.samples),
            f"{r.seconds:.2f}",
            f"{r.rate:.4g}",
            ", ".join(r.signals),
            str(r.dropped),
            str(r.missing),
            "; ".join(f"{g.length:.3g} s at {g.into:.3f} s" for g in r.gaps) or "none",
        )
        for r in p.runs
    ]
    return [
        f"robot: {len(p.joints)} active joints ({', '.join(p.joints)}), {p.base_parameters} base parameters",
        titled_table(
            "Runs, read as identify reads them",
            ("run", "role", "samples", "s", "Hz", "signals", "dropped", "missing", "gaps (cut there)"),
            rows,
        ),
        f"fit: {cfg.method}, {cfg.fit}; declared effects: {', '.join(p.declared) or 'none'}; "
        f"{p.candidates} candidate terms the search may add",
        *[f"warning: {w}" for w in p.warnings],
        "identify would start",
    ]


def preprocessing_notes(report: Report) -> list[str]:
    """The cut-off used (and where it came from), the rows dropped per run, the warnings and the
    joints the model predicts worse than the rigid body."""
    worse = [report.joints[j] for j in np.flatnonzero(report.worse_than_rigid_body)]
    return (
        [f"low-pass cut-off {report.cutoff:.3g} Hz ({report.cutoff_source}); stored as cutoff_Hz"]
        + [f"data.bad_rows: dropped {rows} unusable row(s) of {name}" for name, rows in report.dropped]
        + [f"warning: {w}" for w in report.warnings]
        + ([f"warning: worse than the rigid body on the validation data: {', '.join(worse)}"] if worse else [])
    )


def identification(report: Report) -> list[Table | str]:
    """The before/after error table, the fits compared, the ladder, the selection's steps, the chosen
    effects, what was absorbed, the base parameters."""
    choice = report.fit_choice
    other_name, other = (
        ("least squares", report.relative_least_squares)
        if choice.is_consistent
        else ("consistent", report.relative_consistent)
    )
    extra = other is not None
    errors = titled_table(
        f"Validation torque error, rigid body only → with the chosen effects, {choice.name} "
        f"({report.validation_samples} instants that neither the fit nor the selection saw)",
        ("joint", "RMS τ [Nm]", "before [Nm]", "after [Nm]", "before [%]", "after [%]")
        + ((f"{other_name} [%]",) if extra else ()),
        [
            (
                name + ("" if report.live[j] else " (no signal)"),
                f"{report.rms_torque[j]:.3f}",
                f"{report.rms_before[j]:.3f}",
                f"{report.rms_after[j]:.3f}",
                f"{report.relative_before[j]:.1f}",
                f"{report.relative_after[j]:.1f}",
                *((f"{other[j]:.1f}",) if extra else ()),
            )
            for j, name in enumerate(report.joints)
        ],
        f"mean{'' if report.live.all() else ' of the joints with signal'}: before "
        f"{report.mean(report.relative_before):.1f} %, after {report.mean(report.relative_after):.1f} % "
        f"({choice.name})" + (f", {other_name} {report.mean(other):.1f} %" if extra else ""),
    )
    return [errors, *fits(report), *_selection_tables(report), *noise_table(report)]


def fits(report: Report) -> list[Table]:
    """The candidate fits and their cross-validated errors, when there were several."""
    choice = report.fit_choice
    if len(choice.names) < 2:
        return []
    validation = {
        "least squares": report.mean(report.relative_least_squares),
        "consistent": None if report.relative_consistent is None else report.mean(report.relative_consistent),
    }
    best_consistent = min(
        (k for k, lam in enumerate(choice.regularization) if not np.isnan(lam)), key=lambda k: choice.cv_error[k]
    )
    rows = []
    for k, name in enumerate(choice.names):
        kind = "least squares" if np.isnan(choice.regularization[k]) else "consistent"
        shown = kind == "least squares" or k == best_consistent
        rows.append(
            (
                name + (" (chosen)" if k == choice.chosen else ""),
                f"{choice.cv_error[k]:.2f}",
                f"{validation[kind]:.2f}" if shown and validation[kind] is not None else "",
            )
        )
    return [
        *models(report),
        titled_table(
            "Fits of the chosen model, scored on the selection's folds",
            ("fit", "cross-validated [%]", "validation [%]"),
            rows,
            f"chosen: {choice.name}, cross-validated {abs(choice.lead):.2f} % points "
            f"{'below' if choice.lead >= 0 else 'above'} the next" + _why_not_least_squares(choice),
        ),
    ]


def _why_not_least_squares(choice) -> str:
    """Why least squares, lower on the folds, is not the reported fit (empty when it is, or is not lower)."""
    if choice.lead >= 0 or not choice.is_consistent:
        return ""
    if choice.admission is Admission.PAIRED:
        return "; least squares is lower on average but the folds disagree by more than its gain (paired test)"
    return (
        "; least squares is lower but not chosen: time blocks of one recording see motion next to the fit's and "
        "do not charge least squares for directions a new motion excites, so it must be "
        f"{100 * choice.margin:.0f} % below the consistent fit's (identification.least_squares_margin)"
    )


def models(report: Report) -> list[Table]:
    """The models compared with the fits (each search's start and end): the best fit of each and J."""
    choice = report.fit_choice
    if len(choice.models) < 2:
        return []
    rows = []
    for k, (label, model) in enumerate(zip(choice.labels, choice.models)):
        best = int(np.nanargmin(choice.objective[k]))
        rows.append(
            (
                label + (" (chosen)" if k == choice.model else ""),
                f"{choice.effects(k, best):.4g}",
                f"{choice.cv[k, 0]:.2f}" if choice.names[0] == "least squares" else "",
                choice.names[best],
                f"{choice.cv[k, best]:.2f}",
                f"{choice.objective[k, best]:.4f}",
            )
        )
    return [
        titled_table(
            f"Models and fits scored together: {choice.admission.fit_objective}; the lowest wins",
            ("model", "effects", "least squares CV [%]", "best fit", "its CV [%]", "J"),
            rows,
        )
    ]


def _selection_tables(report: Report) -> list[Table | str]:
    """The ladder, the search, the effects, what was absorbed, the base parameters."""
    sel = report.selection
    consistent = report.consistent
    ladder = titled_table(
        "What each effect bought: mean relative error after each step",
        ("step", "cross-validated [%]", "validation [%]"),
        [(label, f"{cv:.2f}", f"{val:.2f}") for label, cv, val in report.ladder],
        f"cross-validated: {sel.folds} folds of the fit data by {sel.folds_by} "
        "(what the selection minimizes); "
        "validation: data it never saw",
    )
    order = {t: k + 1 for k, t in enumerate(sel.terms)}
    b, between = len(report.base_names), sel.fit.between
    spread = (f"std, {sel.fit.spread_by}",) if between is not None else ()
    effects = titled_table(
        "Effects, in the order they were added (declared ones first)",
        ("#", "effect", "joint", "shape [rad/s]", "coefficient", "least squares", "std")
        + spread
        + (("consistent",) if consistent else ()),
        [
            (
                str(order[t]),
                t.effect,
                t.where(report.joints) if t.coupling is None else f"motor of {t.where(report.joints)}",
                "" if t.shape is None else f"{t.shape:g}",
                f"{name} [{t.kind.units[0]}]",
                f"{value:.5g}",
                f"{std:.2g}" if np.isfinite(std) else "held at 0",
                *((_std(between[b + k]),) if spread else ()),
                *((f"{consistent.effects[k]:.5g}",) if consistent else ()),
            )
            for k, (t, name, value, std) in enumerate(report.effect_values())
        ],
    )
    params = titled_table(
        "Identified base parameters",
        ("base parameter", "least squares", "std") + spread + (("consistent",) if consistent else ()),
        [
            (
                name,
                f"{value:.5g}",
                f"{std:.2g}",
                *((_std(between[k]),) if spread else ()),
                *((f"{consistent.base[k]:.5g}",) if consistent else ()),
            )
            for k, (name, value, std) in enumerate(zip(report.base_names, sel.fit.x, sel.fit.std))
        ],
    )
    absorbed = (
        [
            "not separately identifiable (in the span of the base parameters): "
            + ", ".join(t.label(report.joints) for t in sel.absorbed)
        ]
        if sel.absorbed
        else []
    )
    stds = [STDS + (f" {SPREADS[sel.fit.spread_by].format(count=sel.fit.groups)}" if spread else "")]
    return [ladder, *search(report), effects, *absorbed, *_guarded(report), params, *stds, *_unresolved(report)]


#: What the std columns are.
STDS = (
    "std: of the noise the fit residuals show, the model taken as right (an effect the model lacks makes "
    "recordings of one trajectory agree better, and distinct trajectories worse, than it says)"
)
SPREADS = {
    "trajectories": "std, trajectories: the spread between the {count} distinct trajectories fitted, the model's "
    "error included (recordings of one trajectory count once: data.runs[].trajectory)",
    "time blocks": "std, time blocks: the spread between the {count} time blocks of the folds (fewer than 3 "
    "distinct trajectories), the model's error within this motion and any drift included; another motion "
    "can differ by more",
}


def _std(value: float) -> str:
    """A standard deviation as printed: two digits, or why there is none."""
    return f"{value:.2g}" if np.isfinite(value) else "-"


#: A base parameter whose standard deviation is this many times its magnitude is not told from 0.
UNRESOLVED = 10.0


def _unresolved(report: Report) -> list[str]:
    """A line naming the base parameters whose std is ``UNRESOLVED`` times their least-squares value
    or more (a direction the data hardly excites, or a rounding of the robot's file), if any."""
    fit = report.selection.fit
    names = [n for n, x, s in zip(report.base_names, fit.x, fit.std) if s >= UNRESOLVED * abs(x)]
    if not names:
        return []
    return [f"std ≥ {UNRESOLVED:g} × the value (the data cannot tell them from 0): {', '.join(names)}"]


def _guarded(report: Report) -> list[str]:
    """A line naming the q range [rad] each chosen position effect is held to, if any."""
    joints = sorted({t.joint for t in report.selection.terms if t.kind.position})
    if not joints:
        return []
    if report.q_range is None:
        return ["position effects extrapolate outside the fit data's q range (position_guard off)"]
    ranges = ", ".join(f"{report.joints[j]} [{report.q_range[j, 0]:.3f}, {report.q_range[j, 1]:.3f}]" for j in joints)
    return [f"position effects held at their value at the ends of the fit data's q range [rad]: {ranges}"]
