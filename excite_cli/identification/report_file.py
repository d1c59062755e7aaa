"""The ``identify`` report as HDF5: ``/identification/...`` (base parameters, effects, validation
errors, the physically consistent fit), plus ``/regressor`` and ``/robot/base_parameter_names`` so the
file can serve as prior data C₀ of ``optimize`` (Eq. 41). Units are attributes of each dataset."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from excite_cli.base_parameters import BaseParameters
from excite_cli.identification.physical import body_properties
from excite_cli.identification.pipeline import Report, effect_values
from excite_cli.output import atomic_h5, write_strings
from excite_cli.robot import Robot


def write_identification(path: Path, report: Report, robot: Robot, base: BaseParameters, source_text: str,
                         regressor: list[np.ndarray], method: str) -> None:
    """Write (atomically) an ``identify`` report.

    Args:
        report: the :class:`~excite_cli.identification.pipeline.Report`.
        source_text: the identify config's text.
        regressor: base regressor rows of all samples, in parts ((M_k, b) each, e.g. fit and validation).
        method: ``wls`` or ``ls``.

    Raises:
        ExciteError: the file cannot be written.
    """
    sel, b = report.selection, base.count
    with atomic_h5(path) as f:
        f.attrs["config"] = source_text
        group = f.create_group("robot")
        write_strings(group, "joint_names", robot.joint_names)
        write_strings(group, "base_parameter_names", base.names)
        rows = f.create_dataset("regressor", data=np.vstack(regressor) if regressor else np.zeros((0, b)))
        rows.attrs["description"] = "base regressor of all preprocessed samples, fit then validation (prior data C0, Eq. 41)"
        g = f.create_group("identification")
        g.attrs["method"], g.attrs["cutoff_Hz"] = method, report.cutoff
        g.attrs["fit_samples"], g.attrs["validation_samples"] = report.fit_samples, report.validation_samples
        g.attrs["dropped_rows"] = "; ".join(f"{name}: {rows}" for name, rows in report.dropped) or "none"
        write_strings(g, "joint_names", report.joints)
        write_strings(g, "base_parameter_names", report.base_names)
        consistent = report.consistent
        g.create_dataset("base_parameters", data=sel.fit.x[:b] if consistent is None else consistent.base)
        g.create_dataset("base_parameters_unconstrained", data=sel.fit.x[:b])
        g.create_dataset("base_parameters_std", data=sel.fit.std[:b])
        g.create_dataset("base_parameters_rigid_only", data=sel.rigid.x)
        g.create_dataset("physically_consistent", data=consistent is not None)
        if consistent is not None:
            _write_consistent(g, report, robot)
        _write_effects(g, report)
        _write_validation(g, report)


def _write_effects(g: h5py.Group, report: Report) -> None:
    """The chosen effects in the order they were added, declared ones flagged, and what was absorbed."""
    sel, rows = report.selection, effect_values(report)
    effects = np.zeros(len(rows), dtype=[("order", "i4"), ("effect", h5py.string_dtype()), ("coefficient", h5py.string_dtype()),
                                         ("joint", h5py.string_dtype()), ("value", "f8"), ("std", "f8"), ("declared", "?"),
                                         ("value_consistent", "f8")])
    effects["value_consistent"] = np.nan if report.consistent is None else report.consistent.effects
    declared = {(e, report.joints[j]) for e, j in sel.effects[: sel.declared]}
    order = {key: k + 1 for k, key in enumerate((e, report.joints[j]) for e, j in sel.effects)}
    for row, (effect, coefficient, joint, value, std) in zip(effects, rows):
        row["order"], row["effect"], row["coefficient"], row["joint"] = order[(effect, joint)], effect, coefficient, joint
        row["value"], row["std"], row["declared"] = value, std, (effect, joint) in declared
    g.create_dataset("effects", data=effects)
    write_strings(g, "absorbed_effects", [f"{e}:{report.joints[j]}" for e, j in sel.absorbed])


def _write_validation(g: h5py.Group, report: Report) -> None:
    """Torque errors on the held-out data: per joint, and per run."""
    n, runs = len(report.joints), report.per_run()
    table = np.zeros(len(runs), dtype=[("run", h5py.string_dtype()), ("instants", "i8"), ("rms_before", "f8", n),
                                       ("rms_after", "f8", n), ("relative_after", "f8", n)])
    for row, (name, count, before, after, torque) in zip(table, runs):
        row["run"], row["instants"], row["rms_before"], row["rms_after"] = name, count, before, after
        row["relative_after"] = 100.0 * after / np.where(torque > 0, torque, 1.0)
    g.create_dataset("validation_runs", data=table).attrs["units"] = "rms in Nm; relative_after in % of the run's RMS torque"
    for name, values, unit in (("rms_before", report.rms_before, "Nm"), ("rms_after", report.rms_after, "Nm"),
                               ("rms_torque", report.rms_torque, "Nm"), ("relative_before", report.relative_before, "%"),
                               ("relative_after", report.relative_after, "%")):
        g.create_dataset(name, data=values).attrs["unit"] = unit


def _write_consistent(g: h5py.Group, report: Report, robot: Robot) -> None:
    """The physically consistent fit: standard parameters, per-body properties beside the URDF's,
    active constraints, its validation errors."""
    consistent = report.consistent
    g.create_dataset("standard_parameters", data=consistent.standard).attrs["unit"] = "kg, kg m, kg m^2 (pinocchio order per body)"
    write_strings(g, "standard_parameter_names", robot.parameter_names)
    g.attrs["solver_status"] = consistent.status
    write_strings(g, "active_constraints", consistent.active)
    urdf = robot.urdf_parameters()
    bodies = np.zeros(len(robot.body_names), dtype=[("body", h5py.string_dtype()), ("mass", "f8"), ("com", "f8", 3),
                                                     ("principal_moments", "f8", 3), ("inertia_com", "f8", (3, 3)),
                                                     ("urdf_mass", "f8"), ("urdf_com", "f8", 3), ("urdf_principal_moments", "f8", 3),
                                                     ("pseudo_inertia_min_eigenvalue", "f8")])
    for i, row in enumerate(bodies):
        m, c, I, moments = body_properties(consistent.standard[10 * i: 10 * i + 10])
        um, uc, _, umoments = body_properties(urdf[10 * i: 10 * i + 10])
        row["body"], row["mass"], row["com"], row["principal_moments"], row["inertia_com"] = robot.body_names[i], m, c, moments, I
        row["urdf_mass"], row["urdf_com"], row["urdf_principal_moments"] = um, uc, umoments
        row["pseudo_inertia_min_eigenvalue"] = consistent.min_eigenvalues[i]
    table = g.create_dataset("bodies", data=bodies)
    table.attrs["units"] = "mass kg, com m, moments and inertia kg m^2 (about the CoM, body axes)"
    g.create_dataset("rms_consistent", data=report.rms_consistent).attrs["unit"] = "Nm"
    g.create_dataset("relative_consistent", data=report.relative_consistent).attrs["unit"] = "%"
