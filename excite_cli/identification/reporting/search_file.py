"""The effects an identify report found and the search that found them, as its HDF5 file holds them
(``/identification``: the effects table and its couplings, the ladder, the kept search's steps,
every move tried, every start)."""

from __future__ import annotations

import h5py
import numpy as np

from excite_cli.h5 import write_strings, write_table
from excite_cli.identification.choice.admission import Admission
from excite_cli.identification.reporting.report import Report

STR = h5py.string_dtype()


def _term_fields(term, joints: list[str]) -> tuple[str, str, float]:
    """(effect, joint (a coupled term: its motor coordinate), shape velocity [rad/s] or NaN) of a term."""
    return term.effect, term.where(joints), np.nan if term.shape is None else term.shape


def write_effects(g: h5py.Group, report: Report) -> None:
    """The chosen effects in the order they were added, declared ones flagged, with units, and what
    was absorbed."""
    sel, rows = report.selection, report.effect_values()
    effects = np.zeros(
        len(rows),
        dtype=[
            ("order", "i4"),
            ("effect", STR),
            ("coefficient", STR),
            ("joint", STR),
            ("shape", "f8"),
            ("value", "f8"),
            ("std", "f8"),
            ("std_between_trajectories", "f8"),
            ("std_between_time_blocks", "f8"),
            ("unit", STR),
            ("declared", "?"),
            ("value_consistent", "f8"),
        ],
    )
    effects["value_consistent"] = np.nan if report.consistent is None else report.consistent.effects
    between = sel.fit.between
    for spread_by in ("trajectories", "time blocks"):
        field = f"std_between_{spread_by.replace(' ', '_')}"
        effects[field] = between[len(report.base_names) :] if sel.fit.spread_by == spread_by else np.nan
    order = {t: k + 1 for k, t in enumerate(sel.terms)}
    for row, (term, coefficient, value, std) in zip(effects, rows):
        row["order"], row["coefficient"], row["value"], row["std"] = order[term], coefficient, value, std
        row["effect"], row["joint"], row["shape"] = _term_fields(term, report.joints)
        row["unit"], row["declared"] = term.kind.units[0], order[term] <= sel.declared
    data = g.create_dataset("effects", data=effects)
    data.attrs["shape_unit"] = "rad/s (Stribeck v_s, held v_h; NaN for other effects)"
    coupling = np.array([t.rows(len(report.joints)) if t.coupling else np.zeros(len(report.joints)) for t, *_ in rows])
    g.create_dataset("effect_coupling", data=coupling.reshape(len(rows), len(report.joints))).attrs["description"] = (
        "per effects row: the motor coordinate's weights over the joints of a coupled term (0 for a joint's own)"
    )
    write_strings(g, "offset_runs", report.offset_runs)
    if report.q_range is not None:
        g.create_dataset("fit_q_range", data=report.q_range).attrs["unit"] = (
            "rad (lowest, highest q per joint over the fit data; position effects are held at these ends outside it)"
        )
    write_strings(g, "absorbed_effects", [t.label(report.joints) for t in sel.absorbed])
    g.create_dataset("cv_error_joint", data=sel.cv_joint).attrs["unit"] = "% (cross-validated on the fit data)"


def write_search(g: h5py.Group, report: Report) -> None:
    """The selection: the ladder (CV and validation error after each step), the kept search's steps,
    every move tried at each step with its gain, and the outcome of every start."""
    ladder = np.array(report.ladder, dtype=[("step", STR), ("cv_error", "f8"), ("validation_error", "f8")])
    g.create_dataset("ladder", data=ladder).attrs["units"] = (
        "% (mean relative RMS torque error: cross-validated on the fit data, on the validation data)"
    )
    sel = report.selection
    move = [
        ("step", "i4"),
        ("move", STR),
        ("effect", STR),
        ("joint", STR),
        ("shape", "f8"),
        ("cv_error", "f8"),
        ("gain", "f8"),
    ]
    steps, tried = [], []
    for k, step in enumerate(sel.steps, start=1):
        steps.append((k, step.move, *_term_fields(step.term, report.joints), step.cv_error, step.gain))
        tried += [(k, m, *_term_fields(t, report.joints), v, step.gain_of(v)) for m, t, v in step.tried]
    units = "cv_error in %, gain in % of the CV error before the step, shape in rad/s"
    written = g.create_dataset("steps", data=np.array(steps, dtype=move))
    written.attrs["units"], written.attrs["admission"] = units, str(sel.admission)
    written.attrs["clear_of_zero_std"] = [step.clear_of_zero for step in sel.steps]  # NaN unless judged by the estimate
    if sel.admission is Admission.PAIRED:  # each step's mean gain over the folds and the margin it passed
        written.attrs["fold_gain_percent"] = [step.fold_gain for step in sel.steps]
        written.attrs["fold_margin_percent"] = [step.fold_margin for step in sel.steps]
        written.attrs["family_margin_percent"] = [step.family_margin for step in sel.steps]
        refused = sel.searches[sel.chosen].refused
        written.attrs["refused_at_stop"] = refused.label(report.joints) if refused else ""
    g.create_dataset("candidates", data=np.array(tried, dtype=move)).attrs["units"] = (
        units + "; every move tried at each step"
    )
    write_table(
        g,
        "searches",
        [
            (s.start, ", ".join(t.label(report.joints) for t in s.terms), s.cv_error, s.objective, len(s.steps), s.stop)
            + (k == sel.chosen,)
            for k, s in enumerate(sel.searches)
        ],
        "start:str effects:str cv_error:f8 objective:f8 steps:i4 stop_reason:str chosen:?",
        units=f"cv_error in %; objective {sel.admission.search_objective}",
    )
