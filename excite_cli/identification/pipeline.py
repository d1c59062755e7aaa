"""``excite identify``: measured runs ─► preprocessing ─► fit / validation split ─► rigid-body fit ─►
effect selection (cross-validated on the fit data) ─► report of the torque error before and after on
the validation data, which neither the fit nor the selection saw."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Callable

import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters, compute_base_parameters
from excite_cli.dynamics.robot import Robot, load_robot
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.effects import EFFECTS
from excite_cli.errors import ExciteError
from excite_cli.identification.choice.consistent_model import consistent_model
from excite_cli.identification.choice.crossval import fold_groups
from excite_cli.identification.choice.fit_choice import choose_fit
from excite_cli.identification.choice.selection import Selection, candidate_terms, motor_couplings, select_effects
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term, rotor_terms
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import least_squares, predict, torque_errors
from excite_cli.identification.fitting.noise_level import BLOCKS, NoiseLevel, measured_noise
from excite_cli.identification.fitting.normal import weighted_fit
from excite_cli.identification.fitting.plausibility import implausible
from excite_cli.identification.measured.measurements import in_sample_validation
from excite_cli.identification.prepared import prepare_data
from excite_cli.identification.reporting.prior_rows import PriorRows, prior_rows
from excite_cli.identification.reporting.report import Report
from excite_cli.identification.reporting.urdf_out import urdf_deviation, write_urdf
from excite_cli.memory import return_freed_memory, trim_freed_memory


def declared_terms(problem: IdentifyProblem, robot: Robot) -> list[Term]:
    """The terms of ``identification.declared_effects`` ({joint or "*": [effects]}); a Stribeck or held
    term starts at the middle of its velocity grid (the selection may move it along the grid).

    Raises:
        ExciteError: a joint that is not active.
    """
    cfg = problem.identification
    out: list[Term] = []
    for name, effects in cfg.declared_effects.items():
        if name != "*" and name not in robot.joint_names:
            raise ExciteError("identification.declared_effects", f"'{name}' is not an active joint")
        joints = range(robot.n_joints) if name == "*" else [robot.joint_names.index(name)]
        for e in effects:
            grid = getattr(cfg, EFFECTS[e].shape_field) if EFFECTS[e].shape_field else None
            for j in joints:
                if all((u.effect, u.joint) != (e, j) for u in out):
                    out.append(Term(e, j, grid[len(grid) // 2] if grid else None))
    return out


def error_ladder(
    val_data: Dataset, selection: Selection, joints: list[str], live: np.ndarray
) -> list[tuple[str, float, float]]:
    """(step, CV error [%], mean relative validation error [%] over the ``live`` (n,) joints) of the
    rigid body, the kept search's start and each of its steps, every model fitted on all fit data with
    the selection's weights: what each effect bought."""
    measured = val_data.tau.reshape(-1, val_data.n)
    search = selection.searches[selection.chosen]
    models = [("rigid body", [], selection.cv_rigid)]
    if search.initial:
        models.append((f"start: {search.start}", search.initial, search.initial_error))
    models += [(step.label(joints), step.terms, step.cv_error) for step in search.steps]
    fitted = (
        (label, cv, predict(val_data, least_squares(selection.normal, terms, selection.weights).x, terms))
        for label, terms, cv in models
    )
    return [(label, cv, float(torque_errors(measured, predicted)[2][live].mean())) for label, cv, predicted in fitted]


def run_identification(
    problem: IdentifyProblem, consistent_beside: bool = False, say: Callable[[str], None] | None = None
) -> tuple[Report, Robot, BaseParameters, PriorRows]:
    """The whole loop on ``problem``'s data; memory follows the decimated data.

    Args:
        consistent_beside: fit the physically consistent model even when ``identification.fit`` is
            ``least_squares`` (the identified URDF needs it).
        say: told what is under way (a line: the run read, the search's step, the model scored).

    Returns:
        The :class:`Report`, the robot, its base parameters and the rows of all samples, fit then
        validation, as prior data C₀ for ``optimize`` (Eq. 41): the base regressor and the chosen
        effects' design columns (:class:`~excite_cli.identification.reporting.prior_rows.PriorRows`).

    Raises:
        ExciteError: bad data or config (see :func:`prepare_data`), or a consistent fit without a
            solution.
    """
    return_freed_memory()  # memory follows the live (decimated) data
    robot = load_robot(problem.robot, problem.folder, joint_rows_only=True, physical=False)
    base = compute_base_parameters(robot)
    declared = declared_terms(problem, robot)  # before any data is read
    cfg = problem.identification
    couplings = motor_couplings(problem.data.transmission, cfg.coupling_ratios, robot.n_joints)
    candidates = candidate_terms(cfg, robot.n_joints, couplings)
    terms = declared + [t for t in candidates + rotor_terms(robot.n_joints, []) if t not in declared]
    data = prepare_data(problem, robot, base, list(dict.fromkeys(terms)), say)  # with the consistent fit's rotors
    fit_data, val_data = data.fit, data.validation
    selection = select_effects(
        fit_data,
        cfg,
        declared,
        margin=1.0 / data.cutoff,
        recordings=fold_groups(data.trajectories, problem.data.runs, cfg.folds_by, data.fitted),
        fitted_offsets=set(np.unique(val_data.run).tolist()) <= set(data.fitted),
        couplings=couplings,
        scored=~data.silent,
        say=say,
        uncertainty=(data.rate, data.trajectories),
    )
    offset_runs = [problem.data.runs[k].label for k in data.fitted]
    selection, choice = choose_fit(selection, robot, base, offset_runs, cfg, consistent_beside, say)
    selection = replace(selection, fit=selection.estimates.reported(selection.terms))
    measured = val_data.tau.reshape(-1, val_data.n)
    before = predict(val_data, selection.rigid.x, [])
    plain = predict(val_data, selection.fit.x, selection.terms)
    consistent, kept = None, selection.terms
    if choice.consistent is not None:
        kept, x = consistent_model(choice.consistent, selection.terms, robot.joint_names)
        consistent = predict(val_data, x, kept)
    after = consistent if choice.is_consistent else plain
    model = (x, kept) if choice.is_consistent else (selection.fit.x, selection.terms)
    levels = noise_levels(fit_data, *model, data.gains[fit_data.run], ~data.silent | data.silent.all())
    rms_after, rms_torque, _ = torque_errors(measured, after)
    ladder = error_ladder(val_data, selection, robot.joint_names, ~data.silent | data.silent.all())
    for d in (fit_data, val_data):  # the candidates not chosen are no longer needed: released before the report
        for t in [t for t in d.blocks if t not in kept]:
            del d.blocks[t]
    trim_freed_memory()
    report = Report(
        joints=robot.joint_names,
        base_names=base.names,
        selection=selection,
        fit_choice=choice,
        rms_before=torque_errors(measured, before)[0],
        rms_after=rms_after,
        rms_torque=rms_torque,
        rms_least_squares=torque_errors(measured, plain)[0],
        rms_consistent=None if consistent is None else torque_errors(measured, consistent)[0],
        validation=val_data,
        predicted_before=before,
        predicted_after=after,
        cutoff=data.cutoff,
        cutoff_source=data.cutoff_source,
        fit_samples=fit_data.time.size,
        validation_samples=val_data.time.size,
        rate=data.rate,
        dropped=data.dropped,
        run_names=[r.label for r in problem.data.runs],
        offset_runs=offset_runs,
        ladder=ladder,
        dead=data.silent,
        q_range=data.q_range,
        warnings=robot.warnings
        + in_sample_validation(problem.data.runs, problem.folder)
        + implausible(fit_data, base.from_standard(robot.urdf_parameters()), robot, choice.consistent)
        + data.silence
        + data.repeats,
        noise_levels=levels,
        noise_gain=float(np.median(data.gains[fit_data.run])),
    )
    if choice.is_consistent:  # the reported model's step: the same effects, the consistent fit
        ladder.append((choice.name, float(choice.cv_error[choice.chosen]), report.mean(report.relative_after)))
    report.warnings += report.fit_disagreement()
    return report, robot, base, prior_rows([fit_data, val_data], selection.terms, robot.joint_names, model)


def noise_levels(
    fit_data: Dataset, x: np.ndarray, terms: list[Term], gain: np.ndarray, live: np.ndarray
) -> list[NoiseLevel | None]:
    """Each ``live`` (n,) joint's noise σ² = a² + (ρτ)² fitted to the residual of the model (coefficients
    ``x`` of the base parameters and ``terms``) on the fit data, each instant's filter ``gain`` (N,): what
    the model cannot explain where it was fitted, not its error away from it; where some joint's noise
    grows with the torque, on the residual of the model's terms refitted with each sample weighed by
    that noise; None for the others; an empty list when the data are too short
    (:func:`~excite_cli.identification.fitting.noise_level.measured_noise`)."""
    measured, predicted = fit_data.tau.reshape(-1, fit_data.n), predict(fit_data, x, terms)
    if measured.shape[0] < 2 * BLOCKS:
        return []

    def refit(weights: np.ndarray) -> np.ndarray:
        return predict(fit_data, weighted_fit(fit_data, terms, weights), terms)

    return measured_noise(measured, predicted, gain, live, refit)


def write_identified_urdf(
    problem: IdentifyProblem, report: Report, robot: Robot, base: BaseParameters, target: Path
) -> float:
    """Write the URDF of the physically consistent fit (:mod:`excite_cli.identification.reporting.urdf_out`) and
    return the largest deviation [Nm] of its RNEA from the identified rigid-body torques.

    Raises:
        ExciteError: no consistent fit in ``report``, or the file cannot be written or loaded back.
    """
    if report.consistent is None:
        raise ExciteError("urdf_out", "needs the physically consistent fit (identification.fit)")
    source, _ = resolve_urdf(problem.robot, problem.folder)
    effects = [(t.effect, c, t.where(report.joints), v) for t, c, v, _ in report.effect_values(consistent=True)]
    write_urdf(
        source,
        target,
        robot,
        report.consistent.standard,
        effects,
        f"physically consistent parameters identified from {problem.source_path or 'measured data'}",
    )
    X, phi_base = base.composition_matrix, report.consistent.bodies_base  # the rotors are comments in a URDF
    return urdf_deviation(problem.robot, robot, lambda q, qd, qdd: robot.regressor(q, qd, qdd) @ X @ phi_base, target)
