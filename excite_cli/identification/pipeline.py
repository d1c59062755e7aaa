"""``excite identify``: measured runs ─► preprocessing ─► fit / validation split ─► rigid-body fit ─►
effect selection ─► report of the torque error before and after on the validation data."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from excite_cli.base_parameters import BaseParameters, compute_base_parameters
from excite_cli.config import IdentifyProblem
from excite_cli.errors import ExciteError
from excite_cli.identification.effects import COEFFICIENTS
from excite_cli.identification.identify import Dataset, Selection, build_dataset, predict, select_effects
from excite_cli.identification.measurements import load_run
from excite_cli.identification.preprocessing import default_cutoff, preprocess
from excite_cli.robot import Robot, load_robot


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

    @property
    def relative_before(self) -> np.ndarray:
        """(n,) RMS error / RMS torque [%] before."""
        return 100.0 * self.rms_before / self.rms_torque

    @property
    def relative_after(self) -> np.ndarray:
        """(n,) RMS error / RMS torque [%] after."""
        return 100.0 * self.rms_after / self.rms_torque


def split(data: Dataset, roles: list[str], blocks: int) -> np.ndarray:
    """(N,) mask of the instants used for fitting: runs by their role; a ``blocks`` run is cut into
    ``blocks`` contiguous time blocks, the even ones for fitting and the odd ones held out.

    Raises:
        ExciteError: nothing left for fitting or for validation.
    """
    fit = np.zeros(data.time.size, dtype=bool)
    for index, role in enumerate(roles):
        rows = np.nonzero(data.run == index)[0]
        if role == "fit":
            fit[rows] = True
        elif role == "blocks":
            block = np.minimum((np.arange(rows.size) * blocks) // rows.size, blocks - 1)
            fit[rows] = block % 2 == 0
    if fit.all() or not fit.any():
        raise ExciteError("data.runs: need data for fitting and for validation (roles fit/validation, or blocks)")
    return fit


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


def run_identification(problem: IdentifyProblem) -> tuple[Report, Robot, BaseParameters, Dataset]:
    """The whole loop on ``problem``'s data.

    Returns:
        The :class:`Report`, the robot, its base parameters and the dataset of all samples (whose
        regressor can serve as prior data C₀ for ``optimize``, Eq. 41).

    Raises:
        ExciteError: bad data or config (see :func:`load_run`, :func:`preprocess`, :func:`split`).
    """
    problem.robot.base_wrench_rows = False
    robot = load_robot(problem)
    base = compute_base_parameters(robot)
    runs = [load_run(r, problem.data, problem, robot.n_joints) for r in problem.data.runs]
    cutoff = problem.preprocessing.cutoff or default_cutoff(runs, problem.preprocessing)
    samples = [preprocess(r, problem.preprocessing, cutoff) for r in runs]
    cfg = problem.identification
    data = build_dataset(robot, base, samples, cfg)
    fit_mask = split(data, [s.role for s in samples], problem.data.validation_blocks)
    fit_data, val_data = data.select(fit_mask), data.select(~fit_mask)
    rate = max(s.filter.rate / s.filter.step for s in samples)
    selection = select_effects(fit_data, val_data, cfg, declared_effects(problem, robot), max(1.0, rate / (2.0 * cutoff)))
    before = predict(val_data, selection.rigid.x, [])
    after = predict(val_data, selection.fit.x, selection.effects)
    measured = val_data.tau.reshape(-1, val_data.n)
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
    )
    return report, robot, base, data


def effect_values(report: Report) -> list[tuple[str, str, str, float, float]]:
    """(effect, coefficient, joint, value, std) for every chosen effect coefficient, in order."""
    b = len(report.base_names)
    rows, k = [], b
    for effect, j in report.selection.effects:
        for coefficient in COEFFICIENTS[effect]:
            rows.append((effect, coefficient, report.joints[j], float(report.selection.fit.x[k]), float(report.selection.fit.std[k])))
            k += 1
    return rows
