"""``excite identify``: measured runs ─► preprocessing ─► fit / validation split ─► rigid-body fit ─►
effect selection ─► report of the torque error before and after on the validation data."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from excite_cli.base_parameters import BaseParameters, compute_base_parameters
from excite_cli.config import with_overrides
from excite_cli.identification.config import IdentifyProblem
from excite_cli.errors import ExciteError
from excite_cli.identification.effects import COEFFICIENTS
from excite_cli.identification.dataset import Dataset, build_datasets
from excite_cli.identification.identify import Selection, design, joint_weights, least_squares, predict, select_effects
from excite_cli.identification.normal import NormalEquations, excited_rank
from excite_cli.identification.measurements import load_run
from excite_cli.identification.physical import ConsistentFit, consistent_fit
from excite_cli.identification.preprocessing import default_cutoff, preprocess
from excite_cli.identification.urdf_out import urdf_deviation, write_urdf
from excite_cli.robot import Robot, load_robot, resolve_urdf


@dataclass
class Report:
    """What ``identify`` found.

    Attributes:
        joints: (n,) active joint names.
        base_names: (b,) base-parameter names.
        selection: chosen effects, fits and selection steps.
        rms_before, rms_after: (n,) validation torque RMS error [Nm], rigid body only / with effects.
        rms_torque: (n,) RMS of the measured validation torques [Nm].
        validation: the validation samples; predicted_before, predicted_after: (N, n) [Nm] on them.
        cutoff: low-pass cut-off of every run [Hz].
        fit_samples, validation_samples: instants used for fitting / validation.
        dropped: (file, rows) left out as unusable, per run with ``data.bad_rows: drop``.
        run_names: (runs,) each configured run's file name (with its crop), indexed by ``Dataset.run``.
        consistent: the physically consistent fit with the same effects, or None.
        rms_consistent: (n,) its validation torque RMS error [Nm] (None without it).
    """

    joints: list[str]
    base_names: list[str]
    selection: Selection
    rms_before: np.ndarray
    rms_after: np.ndarray
    rms_torque: np.ndarray
    validation: Dataset
    predicted_before: np.ndarray
    predicted_after: np.ndarray
    cutoff: float
    fit_samples: int
    validation_samples: int
    dropped: list[tuple[str, int]] = field(default_factory=list)
    run_names: list[str] = field(default_factory=list)
    consistent: ConsistentFit | None = None
    rms_consistent: np.ndarray | None = None

    @property
    def relative_before(self) -> np.ndarray:
        """(n,) RMS error / RMS torque [%] before."""
        return 100.0 * self.rms_before / self.rms_torque

    @property
    def relative_after(self) -> np.ndarray:
        """(n,) RMS error / RMS torque [%] after."""
        return 100.0 * self.rms_after / self.rms_torque

    def per_run(self) -> list[tuple[str, int, np.ndarray, np.ndarray, np.ndarray]]:
        """(run name, instants, RMS error before (n,) [Nm], after (n,) [Nm], RMS torque (n,) [Nm]) of
        each validation run."""
        measured = self.validation.tau.reshape(-1, len(self.joints))
        out = []
        for r in np.unique(self.validation.run):
            rows = self.validation.run == r
            rms = [np.sqrt(np.mean((measured[rows] - p[rows]) ** 2, axis=0)) for p in (self.predicted_before, self.predicted_after)]
            torque = np.sqrt(np.mean(measured[rows] ** 2, axis=0))
            out.append((self.run_names[r] if r < len(self.run_names) else str(r), int(rows.sum()), *rms, torque))
        return out

    @property
    def relative_consistent(self) -> np.ndarray | None:
        """(n,) RMS error / RMS torque [%] of the physically consistent fit, or None."""
        return None if self.rms_consistent is None else 100.0 * self.rms_consistent / self.rms_torque


def declared_effects(problem: IdentifyProblem, robot: Robot) -> list[tuple[str, int]]:
    """(effect, joint index) pairs of ``identification.declared_effects`` ({joint or "*": [effects]}).

    Raises:
        ExciteError: a joint that is not active.
    """
    out = []
    for name, effects in problem.identification.declared_effects.items():
        if name != "*" and name not in robot.joint_names:
            raise ExciteError(f"identification.declared_effects: '{name}' is not an active joint")
        joints = range(robot.n_joints) if name == "*" else [robot.joint_names.index(name)]
        out += [(e, j) for e in effects for j in joints if (e, j) not in out]
    return out


def run_identification(problem: IdentifyProblem) -> tuple[Report, Robot, BaseParameters, list[np.ndarray]]:
    """The whole loop on ``problem``'s data. The runs at their own rate are released once they are
    filtered and decimated, so memory follows the decimated data.

    Returns:
        The :class:`Report`, the robot, its base parameters and the base regressor rows of all
        samples, fit then validation ((M_fit, b), (M_val, b)), which can serve as prior data C₀ for
        ``optimize`` (Eq. 41).

    Raises:
        ExciteError: bad data or config (see :func:`load_run`, :func:`preprocess`, :func:`build_datasets`).
    """
    problem = with_overrides(problem, {"robot.base_wrench_rows": False})  # a copy: the caller's config is not changed
    robot = load_robot(problem)
    base = compute_base_parameters(robot)
    declared = declared_effects(problem, robot)  # before any data is read
    runs = [load_run(r, problem.data, problem, robot.n_joints) for r in problem.data.runs]
    cutoff = problem.preprocessing.cutoff or default_cutoff(runs, problem.preprocessing)
    dropped = [(r.name, r.dropped) for r in runs if r.dropped]
    samples = [preprocess(runs.pop(0), problem.preprocessing, cutoff) for _ in range(len(runs))]
    cfg = problem.identification
    rate = max(s.filter.rate / s.filter.step for s in samples)
    needed = set(cfg.candidates) | {e for e, _ in declared} | {"coulomb"}  # Coulomb: the load column's sign
    fit_data, val_data = build_datasets(robot, base, samples, cfg, problem.data.validation_blocks, needed)
    rigid_only = NormalEquations(fit_data, [])
    rank = excited_rank(rigid_only.system(None, [])[0])
    if rank < base.count:
        raise ExciteError(f"data: the fit runs excite {rank} of the {base.count} base parameters; the robot must move "
                          "through an exciting trajectory (see `excite optimize`), motionless or small motions cannot identify it")
    first = least_squares(rigid_only, [], joint_weights(rigid_only, cfg.method == "wls"))
    fit_data, val_data = fit_data.with_load_columns(first.x), val_data.with_load_columns(first.x)
    selection = select_effects(fit_data, val_data, cfg, declared, max(1.0, rate / (2.0 * cutoff)))
    before = predict(val_data, selection.rigid.x, [])
    after = predict(val_data, selection.fit.x, selection.effects)
    measured = val_data.tau.reshape(-1, val_data.n)
    consistent = fit_consistent(fit_data, selection, robot, base, cfg) if cfg.physical_consistency else None
    rms_consistent = None
    if consistent is not None:
        predicted = predict(val_data, np.concatenate([consistent.base, consistent.effects]), selection.effects)
        rms_consistent = np.sqrt(np.mean((measured - predicted) ** 2, axis=0))
    report = Report(
        joints=robot.joint_names,
        base_names=base.names,
        selection=selection,
        rms_before=np.sqrt(np.mean((measured - before) ** 2, axis=0)),
        rms_after=np.sqrt(np.mean((measured - after) ** 2, axis=0)),
        rms_torque=np.sqrt(np.mean(measured**2, axis=0)),
        validation=val_data,
        predicted_before=before,
        predicted_after=after,
        cutoff=cutoff,
        fit_samples=fit_data.time.size,
        validation_samples=val_data.time.size,
        dropped=dropped,
        run_names=[r.label for r in problem.data.runs],
        consistent=consistent,
        rms_consistent=rms_consistent,
    )
    return report, robot, base, [fit_data.regressor, val_data.regressor]


def fit_consistent(fit_data: Dataset, selection: Selection, robot: Robot, base: BaseParameters, cfg) -> ConsistentFit:
    """The physically consistent fit (:mod:`excite_cli.identification.physical`) of the selected model
    on the fit data, with the selection's per-joint weights (WLS) or none (LS).

    Raises:
        ExciteError: the semidefinite program has no solution.
    """
    b = base.count
    weights = np.ones(fit_data.tau.size) if selection.weights is None else selection.weights[fit_data.joint]
    names = [f"{c} {robot.joint_names[j]}" for e, j in selection.effects for c in COEFFICIENTS[e]]
    return consistent_fit(fit_data.regressor, design(fit_data, selection.effects)[:, b:], fit_data.tau, weights,
                          base.regrouping, robot.urdf_parameters(), names, cfg.regularization, robot.body_names)


def effect_values(report: Report, consistent: bool = False) -> list[tuple[str, str, str, float, float]]:
    """(effect, coefficient, joint, value, std) for every chosen effect coefficient, in order: of the
    selected least-squares fit, or with ``consistent`` of the physically consistent one (std NaN)."""
    b = len(report.base_names)
    values = report.consistent.effects if consistent else report.selection.fit.x[b:]
    stds = np.full(values.size, np.nan) if consistent else report.selection.fit.std[b:]
    rows, k = [], 0
    for effect, j in report.selection.effects:
        for coefficient in COEFFICIENTS[effect]:
            rows.append((effect, coefficient, report.joints[j], float(values[k]), float(stds[k])))
            k += 1
    return rows


def write_identified_urdf(problem: IdentifyProblem, report: Report, robot: Robot, base: BaseParameters, target: Path) -> float:
    """Write the URDF of the physically consistent fit (:mod:`excite_cli.identification.urdf_out`) and
    return the largest deviation [Nm] of its RNEA from the identified rigid-body torques.

    Raises:
        ExciteError: no consistent fit in ``report``, or the file cannot be written or loaded back.
    """
    if report.consistent is None:
        raise ExciteError("--urdf-out: needs the physically consistent fit (identification.physical_consistency)")
    source, _ = resolve_urdf(problem)
    effects = [(e, c, j, v) for e, c, j, v, _ in effect_values(report, consistent=True)]
    write_urdf(source, target, robot, report.consistent.standard, effects,
               f"physically consistent parameters identified from {problem.source_path or 'measured data'}")
    X, phi_base = base.composition_matrix, report.consistent.base
    return urdf_deviation(problem, robot, lambda q, qd, qdd: robot.regressor(q, qd, qdd) @ X @ phi_base, target)
