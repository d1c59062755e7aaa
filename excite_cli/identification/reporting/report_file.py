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
from excite_cli.identification.reporting.search_file import write_effects, write_search

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
        torque = f.create_dataset("predicted_torque", data=np.concatenate(rows.predicted) if rows.predicted else [])
        torque.attrs["description"] = "the reported model's torque of each /regressor row [Nm]: the noise grows with it"
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
        g.attrs["folds_by"], g.attrs["admission"] = sel.folds_by, str(sel.admission)
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
        if sel.fit.between is not None:  # over distinct trajectories or time blocks, model error included
            name = f"base_parameters_std_between_{sel.fit.spread_by.replace(' ', '_')}"
            g.create_dataset(name, data=sel.fit.between[:b]).attrs["groups"] = sel.fit.groups
        g.create_dataset("base_parameters_rigid_only", data=sel.rigid.x)
        g.create_dataset("physically_consistent", data=chosen)
        _write_fits(g, report)
        if consistent is not None:
            _write_consistent(g, report, robot)
        write_effects(g, report)
        write_search(g, report)
        _write_validation(g, report)
        _write_noise_levels(g, report)
        if mjcf is not None:
            write_mujoco_group(f, mjcf, mujoco, report.joints)


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
        units=f"cv_error in %; objective {choice.admission.fit_objective}; the lowest wins",
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


def _write_noise_levels(g: h5py.Group, report: Report) -> None:
    """``/identification/noise_level``: each joint's σ² = a² + (ρτ)² fitted to the residual on the fit data
    (NaN for a dead channel), at the recording's own rate, a's 95 % upper bound beside them; attribute
    ``noise_gain`` the median share g of white noise's variance the low-pass leaves (a and ρ times √g:
    the noise of the report's rows)."""
    if not report.noise_levels:
        return
    names = ("absolute", "absolute_std", "relative", "relative_std", "absolute_upper")
    table = np.zeros(len(report.joints), dtype=[("joint", STR), *((n, "f8") for n in names), ("preferred", STR)])
    for row, joint, level in zip(table, report.joints, report.noise_levels):
        row["joint"] = joint
        for n in names:
            row[n] = np.nan if level is None else getattr(level, n)
        row["preferred"] = "" if level is None else level.preferred
    d = g.create_dataset("noise_level", data=table)
    d.attrs["units"] = "absolute, absolute_std, absolute_upper in Nm; relative, relative_std in 1 (of the torque)"
    d.attrs["noise_gain"] = report.noise_gain


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
