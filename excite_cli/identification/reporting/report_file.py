"""The ``identify`` report as HDF5: ``/identification/...`` (base parameters, effects, the selection's
steps and every candidate it tried, the error ladder, validation errors and predictions, the
physically consistent fit), plus ``/regressor`` (compressed) and ``/robot/base_parameter_names`` so
the file can serve as prior data C₀ of ``optimize`` (Eq. 41). Units are attributes of each dataset."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from excite_cli.config import effective_yaml
from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.robot import Robot
from excite_cli.h5 import atomic_h5, write_parts, write_strings, write_table
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.fitting.bodies import body_properties
from excite_cli.identification.reporting.mjcf_check import MujocoCheck, write_mujoco_group
from excite_cli.identification.reporting.mjcf_out import MjcfModel
from excite_cli.identification.reporting.prior_rows import PriorRows
from excite_cli.identification.reporting.report import Report

STR = h5py.string_dtype()


def write_identification(
    path: Path,
    report: Report,
    robot: Robot,
    base: BaseParameters,
    problem: IdentifyProblem,
    rows: PriorRows,
    mjcf: MjcfModel | None = None,
    mujoco: MujocoCheck | None = None,
) -> None:
    """Write (atomically) an ``identify`` report.

    Args:
        report: the :class:`~excite_cli.identification.pipeline.Report`.
        problem: the identify config that ran (stored as the effective config, every default filled
            in, beside the file's original text).
        rows: the rows of all samples as prior data (base regressor and the design's effect columns, in
            parts: fit, then validation); emptied as the parts are written.
        mjcf, mujoco: the MJCF written and MuJoCo's check of it (``/mujoco``), or None.

    Raises:
        ExciteError: the file cannot be written.
    """
    sel, b = report.selection, base.count
    with atomic_h5(path) as f:
        f.attrs["config"], f.attrs["config_original"] = effective_yaml(problem), problem.source_text
        group = f.create_group("robot")
        write_strings(group, "joint_names", robot.joint_names)
        write_strings(group, "base_parameter_names", base.names)
        write_strings(group, "base_independent_parameters", [robot.parameter_names[k] for k in base.independent])
        group.create_dataset("regrouping_matrix", data=base.regrouping).attrs["description"] = (
            "K (b x p): phi_B = K phi"
        )
        regressor = write_parts(f, "regressor", rows.regressor, b)
        regressor.attrs["description"] = (
            "base regressor of all preprocessed (decimated) samples, fit then validation (C0)"
        )
        regressor.attrs["sample_rate_Hz"] = report.rate
        effects = write_parts(f, "effect_regressor", rows.effects, len(rows.effect_names))
        effects.attrs["description"] = "the chosen effects' columns a design holds, rows as /regressor's (C0)"
        effects.attrs.create("names", rows.effect_names, dtype=STR)
        g = f.create_group("identification")
        g.attrs["method"], g.attrs["cutoff_Hz"], g.attrs["cutoff_source"] = (
            problem.identification.method,
            report.cutoff,
            report.cutoff_source,
        )
        g.attrs["fit_samples"], g.attrs["validation_samples"] = report.fit_samples, report.validation_samples
        g.attrs["dropped_rows"] = "; ".join(f"{name}: {rows}" for name, rows in report.dropped) or "none"
        g.attrs["folds"], g.attrs["min_improvement"] = sel.folds, sel.min_improvement
        g.attrs["folds_by"] = sel.folds_by
        g.attrs["coulomb_velocity_rad_s"] = problem.identification.coulomb_velocity
        g.attrs["cv_error_rigid"], g.attrs["cv_error"] = sel.cv_rigid, report.cv_error
        g.attrs["stop_reason"] = sel.searches[sel.chosen].stop
        g.attrs["warnings"] = "; ".join(report.warnings) or "none"
        write_strings(
            g, "joints_worse_than_rigid_body", [report.joints[j] for j in np.flatnonzero(report.worse_than_rigid_body)]
        )
        write_strings(g, "joint_names", report.joints)
        write_strings(g, "dead_channels", [report.joints[j] for j in np.flatnonzero(~report.live)])
        write_strings(g, "base_parameter_names", report.base_names)
        consistent, chosen = report.consistent, report.fit_choice.is_consistent
        g.create_dataset("base_parameters", data=consistent.base if chosen else sel.fit.x[:b])
        g.create_dataset("base_parameters_unconstrained", data=sel.fit.x[:b])
        g.create_dataset("base_parameters_std", data=sel.fit.std[:b])
        g.create_dataset("base_parameters_rigid_only", data=sel.rigid.x)
        g.create_dataset("physically_consistent", data=chosen)
        _write_fits(g, report)
        if consistent is not None:
            _write_consistent(g, report, robot)
        _write_effects(g, report)
        _write_search(g, report)
        _write_validation(g, report)
        if mjcf is not None:
            write_mujoco_group(f, mjcf, mujoco, report.joints)


def _term_fields(term, joints: list[str]) -> tuple[str, str, float]:
    """(effect, joint (a coupled term: its motor coordinate), shape velocity [rad/s] or NaN) of a term."""
    return term.effect, term.where(joints), np.nan if term.shape is None else term.shape


def _write_effects(g: h5py.Group, report: Report) -> None:
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
            ("unit", STR),
            ("declared", "?"),
            ("value_consistent", "f8"),
        ],
    )
    effects["value_consistent"] = np.nan if report.consistent is None else report.consistent.effects
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


def _write_search(g: h5py.Group, report: Report) -> None:
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
    g.create_dataset("steps", data=np.array(steps, dtype=move)).attrs["units"] = units
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
        units="cv_error in %; objective J = log CV + p log(1 + min_improvement)",
    )


def _write_fits(g: h5py.Group, report: Report) -> None:
    """The candidate fits of the chosen model and their cross-validated errors, the chosen one; every
    model compared under every fit, with J."""
    choice = report.fit_choice
    g.attrs["fit"], g.attrs["fit_lead"] = choice.name, choice.lead
    g.attrs["least_squares_margin"] = choice.margin
    write_table(
        g,
        "fits",
        zip(choice.names, choice.regularization, choice.cv_error),
        "fit:str regularization:f8 cv_error:f8",
        units="cv_error in % of the chosen model on the selection's folds (NaN: the only pair, not cross-validated)",
        chosen=choice.chosen,
    )
    rows = [
        (label, choice.effects(k, f), name, choice.cv[k, f], choice.objective[k, f])
        for k, label in enumerate(choice.labels)
        for f, name in enumerate(choice.names)
    ]
    write_table(
        g,
        "models",
        rows,
        "model:str effects:f8 fit:str cv_error:f8 objective:f8",
        units="cv_error in %; objective J = log CV + effects × log(1 + min_improvement) "
        "(+ log(1 + least_squares_margin) for least squares; a consistent fit's effects leave out armature); "
        "the lowest wins",
        chosen=choice.model * len(choice.names) + choice.chosen,
    )
    g.attrs["model"] = choice.labels[choice.model]
    for name, values, unit in (
        ("rms_least_squares", report.rms_least_squares, "Nm"),
        ("relative_least_squares", report.relative_least_squares, "%"),
    ):
        g.create_dataset(name, data=values).attrs["unit"] = unit


def _write_validation(g: h5py.Group, report: Report) -> None:
    """Torque errors on the validation data (never fitted, never used by the selection): per joint
    and per run, and the measured and predicted torques."""
    n, runs = len(report.joints), report.per_run()
    table = np.zeros(
        len(runs),
        dtype=[
            ("run", STR),
            ("instants", "i8"),
            ("rms_before", "f8", n),
            ("rms_after", "f8", n),
            ("relative_after", "f8", n),
        ],
    )
    for row, (name, count, before, after, torque) in zip(table, runs):
        row["run"], row["instants"], row["rms_before"], row["rms_after"] = name, count, before, after
        row["relative_after"] = 100.0 * after / np.where(report.live & (torque > 0), torque, report.reference)
    g.create_dataset("validation_runs", data=table).attrs["units"] = (
        "rms in Nm; relative_after in % of the run's RMS torque (a dead channel: of the predicted RMS torque)"
    )
    for name, values, unit in (
        ("rms_before", report.rms_before, "Nm"),
        ("rms_after", report.rms_after, "Nm"),
        ("rms_torque", report.rms_torque, "Nm"),
        ("relative_before", report.relative_before, "%"),
        ("relative_after", report.relative_after, "%"),
    ):
        g.create_dataset(name, data=values).attrs["unit"] = unit
    val = g.create_group("validation")
    val.create_dataset("time", data=report.validation.time).attrs["unit"] = "s"
    val.create_dataset("run", data=report.validation.run).attrs["description"] = "index into the config's data.runs"
    for name, values in (
        ("measured", report.validation.tau.reshape(-1, n)),
        ("predicted_before", report.predicted_before),
        ("predicted_after", report.predicted_after),
    ):
        val.create_dataset(name, data=values, compression="gzip").attrs["unit"] = "Nm (filtered and decimated)"


def _write_consistent(g: h5py.Group, report: Report, robot: Robot) -> None:
    """The physically consistent fit: standard parameters, rotor inertias, payloads, per-body properties
    beside the URDF's, active constraints, its validation errors."""
    consistent = report.consistent
    g.create_dataset("standard_parameters", data=consistent.standard).attrs["unit"] = (
        "kg, kg m, kg m^2 (pinocchio order per body)"
    )
    write_strings(g, "standard_parameter_names", robot.parameter_names)
    g.create_dataset("base_parameters_consistent", data=consistent.base).attrs["description"] = "K phi + R a"
    g.create_dataset("rotor_inertias", data=consistent.rotors).attrs["unit"] = "kg m^2 (a, apart from the bodies)"
    write_strings(g, "rotor_joints", consistent.rotor_joints)
    g.create_dataset("rotor_own_columns", data=consistent.own_columns).attrs["description"] = "not in K phi + R a"
    g.create_dataset("payload_parameters", data=consistent.payloads.reshape(-1, 10)).attrs["unit"] = (
        "kg, kg m, kg m^2 (psi on its body, pinocchio order; included in standard_parameters)"
    )
    write_strings(g, "payload_bodies", consistent.payload_bodies)
    g.attrs["solver_status"] = consistent.status
    write_strings(g, "active_constraints", consistent.active)
    urdf, vector, inertia = robot.urdf_parameters(), ("f8", 3), ("f8", (3, 3))
    fields = [("body", STR), ("mass", "f8"), ("com", *vector), ("principal_moments", *vector)]
    fields += [("inertia_com", *inertia), ("urdf_mass", "f8"), ("urdf_com", *vector)]
    fields += [("urdf_principal_moments", *vector), ("pseudo_inertia_min_eigenvalue", "f8")]
    bodies = np.zeros(len(robot.body_names), dtype=fields)
    for i, row in enumerate(bodies):
        m, c, I, moments = body_properties(consistent.standard[10 * i : 10 * i + 10])
        um, uc, _, umoments = body_properties(urdf[10 * i : 10 * i + 10])
        row["body"], row["mass"], row["com"] = robot.body_names[i], m, c
        row["principal_moments"], row["inertia_com"] = moments, I
        row["urdf_mass"], row["urdf_com"], row["urdf_principal_moments"] = um, uc, umoments
        row["pseudo_inertia_min_eigenvalue"] = consistent.min_eigenvalues[i]
    table = g.create_dataset("bodies", data=bodies)
    table.attrs["units"] = "mass kg, com m, moments and inertia kg m^2 (about the CoM, body axes)"
    g.create_dataset("rms_consistent", data=report.rms_consistent).attrs["unit"] = "Nm"
    g.create_dataset("relative_consistent", data=report.relative_consistent).attrs["unit"] = "%"
