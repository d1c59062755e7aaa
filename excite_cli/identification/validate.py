"""``excite validate``: an identified model (an ``identify`` report) scored on other runs, ones that
neither its fit nor its effect selection saw.

The runs of the config are read and preprocessed as ``identify`` does, with the report's cut-off,
and all of their instants are predicted by the report's model (base parameters, then its effects
with their coefficients and shape velocities; the load-dependent Coulomb column from the report's
rigid-body parameters, as in the fit; offsets the mean of the fitted runs' offsets, since a new
run's own offset is unknown). Errors per run and joint: RMS [Nm] and RMS relative to the measured
torque's RMS [%].
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Optional

import numpy as np

from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.robot import load_robot
from excite_cli.errors import ExciteError
from excite_cli.h5 import open_h5, read_strings
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import build_datasets
from excite_cli.identification.fitting.least_squares import predict, torque_errors
from excite_cli.identification.measured.gaps import split_at_gaps
from excite_cli.identification.measured.measurements import load_run
from excite_cli.identification.measured.payload import payload_parameters
from excite_cli.identification.measured.preprocessing import preprocess


@dataclass(frozen=True)
class RunError:
    """One run's validation error: ``name``, ``rms`` (n,) [Nm], ``relative`` (n,) [%], ``instants``."""

    name: str
    rms: np.ndarray
    relative: np.ndarray
    instants: int


@dataclass
class IdentifiedModel:
    """The model an ``identify`` report holds (the fit it reports: least squares or consistent).

    Attributes:
        joints: (n,) active joint names; base_names: (b,) base-parameter names.
        base: (b,) base parameters [SI]; rigid: (b,) the rigid-body-only fit's (for load-dependent terms).
        terms: (effect, joint name, shape or None, coupling or None) of every effect column, in order.
        coefficients: effect coefficients, in the order of ``terms``' columns [SI].
        offset_runs: offset columns (one per fitted run, at least 1).
        cutoff: low-pass cut-off [Hz]; coulomb_velocity: smoothing velocity of sign(q̇) [rad/s].
        q_range: (n, 2) [rad] the fit data's q range per joint that guards the position effects
            (None: a report from before the guard).
    """

    joints: list[str]
    base_names: list[str]
    base: np.ndarray
    rigid: np.ndarray
    terms: list[tuple[str, str, Optional[float], Optional[tuple[float, ...]]]]
    coefficients: np.ndarray
    offset_runs: int
    cutoff: float
    coulomb_velocity: float
    q_range: np.ndarray | None = None


def read_model(path: Path) -> IdentifiedModel:
    """The model of the ``identify`` report at ``path``, every field it uses checked.

    Raises:
        ExciteError: missing or unreadable file, not an identify report, a field missing or of
            another shape than its joints and base parameters give, a value that is not finite, or a
            cut-off or Coulomb velocity that is not a positive number (the field named).
    """
    with open_h5(path, "report") as f:
        if "identification" not in f or "effects" not in f["identification"]:
            raise ExciteError("report", f"{path} is not an excite identify report (no /identification/effects)")
        g = f["identification"]
        for name, unit in (("cutoff_Hz", "Hz"), ("coulomb_velocity_rad_s", "rad/s")):
            value = float(g.attrs.get(name, 0.01))
            if not (np.isfinite(value) and value > 0.0):  # checked like the config field it came from
                raise ExciteError("report", f"{path}: /identification {name} is {value:g}", value, f"> 0 {unit}")
        joints, names = read_strings(g, "joint_names"), read_strings(g, "base_parameter_names")
        rows = g["effects"][()]
        for field in ("effect", "joint", "value"):
            if rows.dtype.names is None or field not in rows.dtype.names:
                raise ExciteError("report", f"{path}: /identification/effects has no field '{field}' (damaged?)")
        consistent = bool(g["physically_consistent"][()]) if "physically_consistent" in g else False
        values = rows["value_consistent"] if consistent and "value_consistent" in rows.dtype.names else rows["value"]
        shapes = rows["shape"] if "shape" in rows.dtype.names else np.full(len(rows), np.nan)
        coupling = (
            _checked(g, "effect_coupling", (len(rows), len(joints)), path)
            if "effect_coupling" in g
            else np.zeros((len(rows), 1))
        )
        terms: list[tuple[str, str, float | None, tuple[float, ...] | None]] = []
        effects, joint_of = (
            [v.decode() if isinstance(v, bytes) else str(v) for v in rows[c]] for c in ("effect", "joint")
        )
        for effect, joint, shape, weights in zip(effects, joint_of, shapes, coupling):
            coupled = tuple(float(w) for w in weights) if np.any(weights) else None
            term = (effect, joint, None if np.isnan(shape) else float(shape), coupled)
            if term not in terms:
                terms.append(term)
        return IdentifiedModel(
            joints,
            names,
            _checked(g, "base_parameters", (len(names),), path),
            _checked(g, "base_parameters_rigid_only", (len(names),), path),
            terms,
            _finite(np.asarray(values, dtype=float), "effects", path),
            max(1, len(g["offset_runs"][()])) if "offset_runs" in g else 1,
            float(g.attrs["cutoff_Hz"]),
            float(g.attrs.get("coulomb_velocity_rad_s", 0.01)),
            _checked(g, "fit_q_range", (len(joints), 2), path) if "fit_q_range" in g else None,
        )


def _checked(group, name: str, shape: tuple[int, ...], path: Path) -> np.ndarray:
    """The report's dataset /identification/``name`` as floats of ``shape``, every value finite.

    Raises:
        ExciteError: missing, of another shape, or not finite (the dataset named).
    """
    if name not in group:
        raise ExciteError("report", f"{path}: /identification/{name} is missing (damaged?)")
    values = np.asarray(group[name][()], dtype=float)
    if values.shape != shape:
        found, wanted = ("x".join(map(str, s)) or "scalar" for s in (values.shape, shape))
        raise ExciteError("report", f"{path}: /identification/{name} has shape {found}", expected=wanted)
    return _finite(values, name, path)


def _finite(values: np.ndarray, name: str, path: Path) -> np.ndarray:
    """``values``, refused where one is NaN or infinite (the dataset named)."""
    if not np.all(np.isfinite(values)):
        raise ExciteError("report", f"{path}: /identification/{name} holds NaN or infinite values (damaged?)")
    return values


def validate_model(report: Path, problem: IdentifyProblem) -> list[RunError]:
    """Score the model of ``report`` on every run of ``problem`` (their roles are ignored; a run's
    offset is the mean of the report's fitted runs' offsets, a run's known payload is taken out).

    Raises:
        ExciteError: a report for another robot (joints or base parameters differ), bad data or
            config (as ``identify``).
    """
    model = read_model(report)
    robot = load_robot(problem.robot, problem.folder, joint_rows_only=True, physical=False)
    base = compute_base_parameters(robot)
    if model.joints != robot.joint_names:
        raise ExciteError("report", f"{report} was identified for other joints than the config's robot")
    order = base.column_order(model.base_names, "report", report)  # the same base, maybe in another order
    model = replace(model, base_names=base.names, base=model.base[order], rigid=model.rigid[order])
    terms = [
        Term(e, int(np.flatnonzero(c)[0]), s, c) if c else Term(e, robot.joint_names.index(j), s)
        for e, j, s, c in model.terms
    ]
    needed = terms + [Term("coulomb", j) for j in range(robot.n_joints)]
    errors = []
    for k, run in enumerate(problem.data.runs):
        pieces = split_at_gaps(  # a gap is never interpolated across, as in identify
            load_run(run.model_copy(update={"role": "validation"}), problem.data, robot.joint_names, problem.folder)
        )
        samples = [preprocess(piece, problem.preprocessing, model.cutoff) for piece in pieces]
        payload = [payload_parameters(robot, run.payload, f"data.runs[{k}].payload") if run.payload else None]
        payload *= len(samples)
        _, data, _ = build_datasets(
            robot,
            base,
            samples,
            needed,
            model.coulomb_velocity,
            problem.data.validation_blocks,
            payload,
            split=False,
            offset_runs=model.offset_runs,
            q_range=model.q_range,
        )
        data = data.with_load_columns(model.rigid, [t for t in terms if t.kind.two_stage])
        predicted = predict(data, np.concatenate([model.base, model.coefficients]), terms)
        rms, _, relative = torque_errors(data.tau.reshape(-1, data.n), predicted)
        errors.append(RunError(run.label, rms, relative, data.time.size))
    return errors
