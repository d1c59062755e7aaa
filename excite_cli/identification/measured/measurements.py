"""Measured runs in (any format of :mod:`excite_cli.identification.measured.files`), mapped to time, q, (q̇,
q̈) and τ (or motor current × torque constants), in SI units and the robot's sign conventions, with
unusable rows stopped on or dropped and counted."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from excite_cli.config import resolve_path
from excite_cli.errors import ExciteError, FileNotFound
from excite_cli.identification.data_config import ColumnsConfig, DataConfig, RunConfig
from excite_cli.identification.measured.bags import bag_columns, is_bag, read_bag
from excite_cli.identification.measured.files import Table, read_table
from excite_cli.identification.measured.joining import join_tables


@dataclass(frozen=True)
class Run:
    """One measured run in SI units.

    Attributes:
        name: file name.
        role: ``fit``, ``validation`` or ``blocks`` (split into alternating time blocks).
        time: (T,) strictly increasing [s].
        q: (T, n) [rad]; qd, qdd: (T, n) [rad/s, rad/s²] or None when to be differentiated.
        tau: (T, n) joint torques [Nm].
        dropped: rows left out as unusable (``data.bad_rows: drop``).
    """

    name: str
    role: str
    time: np.ndarray
    q: np.ndarray
    qd: Optional[np.ndarray]
    qdd: Optional[np.ndarray]
    tau: np.ndarray
    dropped: int = 0


#: Values beyond this magnitude (rad, rad/s, rad/s², Nm, A) are corrupt, not measured. Time is only
#: checked for being finite and increasing: loggers write Unix or ROS time (1.5e9 s).
IMPLAUSIBLE = 1e6


def _column(table: Table, cols: ColumnsConfig, key: int | str, field: str, path: Path) -> np.ndarray:
    """(T,) one column in SI units: times its ``data.columns.factors`` entry, if any."""
    values = table.column(key, field, path)
    factor = cols.factors.get(str(key))
    return values if factor is None else values * factor


def _matrix(table: Table, cols: ColumnsConfig, field: str, path: Path, n: int) -> np.ndarray:
    keys = getattr(cols, field)
    if len(keys) != n:
        raise ExciteError(f"data.columns.{field}", f"{len(keys)} columns for the robot's {n} active joints")
    return np.column_stack([_column(table, cols, key, field, path) for key in keys])


def _usable(time: np.ndarray, signals: dict[str, np.ndarray]) -> tuple[np.ndarray, str]:
    """(T,) rows whose values are finite and plausible, keeping time strictly increasing, and the
    first problem in words (empty when every row is usable)."""
    ok = np.ones(time.size, dtype=bool)
    problem = ""
    for name, values in signals.items():
        bounded = np.isfinite(values) & (name == "time" or np.abs(values) < IMPLAUSIBLE)  # time may be absolute
        bad = ~np.all(bounded, axis=1)
        if bad.any() and not problem:
            kind = (
                "NaN or missing value" if not np.all(np.isfinite(values[bad])) else f"a value beyond ±{IMPLAUSIBLE:g}"
            )
            problem = f"{kind} in {name} at data row {int(np.flatnonzero(bad)[0]) + 1}"
        ok &= ~bad
    latest = -np.inf
    for k in np.flatnonzero(ok):  # time going backwards or repeated: keep the first of each
        if time[k] <= latest:
            ok[k] = False
            if not problem:
                problem = f"time is not strictly increasing at data row {k + 1} ({time[k]:g} s)"
        else:
            latest = time[k]
    return ok, problem


#: A position further than this many joint ranges (or 2π for a joint without limits) outside the
#: limits is not a joint angle: motor angles (× the gear ratio) or another unit.
RANGE_SLACK = 1.0
#: A given velocity above this many times the joint's velocity limit is not a joint velocity.
VELOCITY_SLACK = 3.0
#: A torque channel whose samples are exact zeros this often carries no signal.
SILENT = 0.5


def check_against_limits(
    run: Run, joints: list[str], lower: np.ndarray, upper: np.ndarray, velocity: np.ndarray
) -> Run:
    """Refuse joint positions far outside the robot's limits (``RANGE_SLACK`` ranges beyond them; a joint
    whose URDF gives no range, lower = upper, is not judged) and
    given velocities far beyond them (``VELOCITY_SLACK`` times the limit): motor-side signals or
    another unit.

    Args:
        run: a loaded run (joint side); joints: (n,) names; lower, upper: (n,) position limits [rad];
        velocity: (n,) velocity limits [rad/s] (0 or inf: none).

    Returns:
        ``run``, unchanged.

    Raises:
        ExciteError: naming the column's field, the joint, the value and the limits, with the hint
            that the column may hold motor angles.
    """
    hint = "motor angles? (give data.transmission and data.motor_side: true, or data.angle_unit)"
    span = np.where(np.isfinite(upper - lower), upper - lower, 2 * np.pi)
    lo, hi = run.q.min(axis=0), run.q.max(axis=0)
    ranged = upper > lower  # a URDF revolute joint without lower/upper (read as [0, 0]) has no range to judge by
    far = ranged & ((lo < lower - RANGE_SLACK * span) | (hi > upper + RANGE_SLACK * span))
    if far.any():
        j = int(np.flatnonzero(far)[0])
        value = lo[j] if lo[j] < lower[j] - RANGE_SLACK * span[j] else hi[j]
        raise ExciteError(
            "data.columns.q",
            f"{run.name}: {joints[j]} reaches {value:.4g} rad, far outside its limits [{lower[j]:.3g}, "
            f"{upper[j]:.3g}] rad; {hint}",
        )
    if run.qd is not None:
        limit = np.where((velocity > 0) & np.isfinite(velocity), velocity, np.inf)
        fastest = np.abs(run.qd).max(axis=0)
        far = fastest > VELOCITY_SLACK * limit
        if far.any():
            j = int(np.flatnonzero(far)[0])
            raise ExciteError(
                "data.columns.qd",
                f"{run.name}: {joints[j]} reaches {fastest[j]:.4g} rad/s, {fastest[j] / limit[j]:.3g} times its "
                f"velocity limit {limit[j]:.3g} rad/s; {hint}",
            )
    return run


def in_sample_validation(runs: list[RunConfig], folder: Path | None) -> list[str]:
    """Warnings, one per validation run that is a fit run's recording over overlapping times (the
    same files, crops that overlap by more than an instant: crops that touch, fit [0.1, 5.3] s and
    validation [5.3, 7.5] s, are apart): its "validation" error is in-sample."""

    def span(run: RunConfig) -> tuple[float, float]:
        return run.crop if run.crop is not None else (-np.inf, np.inf)

    def files(run: RunConfig) -> list[Path]:
        return [resolve_path(f, folder) for f in run.files]

    out = []
    for v in (r for r in runs if r.role == "validation"):
        for f in (r for r in runs if r.role == "fit" and files(r) == files(v)):
            if span(f)[0] < span(v)[1] and span(v)[0] < span(f)[1]:  # crops that only touch share no motion
                out.append(
                    f"{v.label}: the validation run is the fit run {f.label} over the same times, so its error "
                    "is in-sample (crop them apart, or validate on another recording)"
                )
    return out


def silent_channels(runs: list[Run], joints: list[str]) -> np.ndarray:
    """(n,) the joints whose torque samples are exact zeros at least ``SILENT`` of the time over
    ``runs``: a channel with no signal (a joint not recorded, a sensor off).

    Raises:
        ExciteError: (``data.runs``) a channel silent in one recording that the others record: its
            zeros would be fitted as the joint's torque (the channel is the file's, not the joint's).
    """
    zeros = [np.count_nonzero(r.tau == 0.0, axis=0) for r in runs]
    silent = sum(zeros) >= SILENT * sum(r.time.size for r in runs)
    for run, z in zip(runs, zeros):
        alone = (z >= SILENT * run.time.size) & ~silent
        if np.any(alone):
            named = ", ".join(joints[j] for j in np.flatnonzero(alone))
            raise ExciteError(
                "data.runs",
                f"{run.name}: the torque of {named} is exact zeros over "
                f"{100 * z[alone].max() / run.time.size:.0f} % of the run while the other runs record it: a channel "
                "this recording did not record; leave the run out or give its torque column",
            )
    return silent


def check_joint_lists(data: DataConfig, n: int) -> None:
    """Every per-joint list of ``data`` (signs, torque constants, the transmission's gear ratios)
    has one entry per active joint: a list for other joints would act on the wrong ones.

    Raises:
        ExciteError: naming the field, its length and ``n``.
    """
    lists = {
        "data.signs": data.signs,
        "data.torque_constants": data.torque_constants,
        "data.transmission.gear_ratios": None if data.transmission is None else data.transmission.gear_ratios,
    }
    for field, values in lists.items():
        if values is not None and len(values) != n:
            raise ExciteError(
                field, f"{len(values)} values for {n} active joint{'s' * (n != 1)}", len(values), f"{n}, one per joint"
            )


def _columns_are_the_bags(data: DataConfig, folder: Path | None) -> bool:
    """Whether ``data.columns`` describe the bags: given, and every run a ROS bag. Where data files
    are among the runs, the columns are theirs and a bag's joints are matched by name."""
    return data.columns is not None and all(is_bag(resolve_path(r.files[0], folder)) for r in data.runs)


def load_run(run: RunConfig, data: DataConfig, joints: list[str], folder: Path | None = None) -> Run:
    """Read, convert and validate one run (CSV with or without header, NPZ, MAT or HDF5, see
    :mod:`excite_cli.identification.measured.files`; a ROS bag, see :mod:`excite_cli.identification.measured.bags`).

    Args:
        run: the run's entry of ``data.runs``.
        data: the data section (columns, units, gains, signs, bad rows).
        joints: the active joints' names (a ROS bag's messages are matched by them).
        folder: the config file's folder, which a relative ``file`` is in.

    Raises:
        ExciteError: missing or unreadable file, wrong column count or name, NaN, missing or
            implausible values (> 1e6) or time not strictly increasing (unless ``bad_rows: drop``),
            a crop that leaves nothing.
    """
    paths = [resolve_path(f, folder) for f in run.files]
    path, n = paths[0], len(joints)
    check_joint_lists(data, n)
    for p in paths:
        if not p.exists():
            raise FileNotFound("data.runs", p)
    drop = data.bad_rows == "drop"
    if len(paths) > 1:
        if data.columns is None:
            raise ExciteError("data.columns", "is required for a run of several files")
        table, cols = (
            join_tables([(p, read_table(p, drop)) for p in paths], data.columns.time, data.sample_rate, drop),
            data.columns,
        )
        cols = cols if cols.time is None else cols.model_copy(update={"time": "time"})
    elif is_bag(path):
        table = read_bag(path, data.topic, joints)
        cols = data.columns if _columns_are_the_bags(data, folder) else ColumnsConfig(**bag_columns(joints, table))
    elif path.is_dir():
        raise ExciteError("data.runs", f"{path} is a folder, not a data file or a ROS 2 bag", path)
    elif data.columns is None:
        raise ExciteError(
            "data.columns", f"is required for {path.name} (only a ROS bag's columns follow the joint names)"
        )
    else:
        table, cols = read_table(path, drop), data.columns
    time = (
        _column(table, cols, cols.time, "time", path)
        if cols.time is not None
        else np.arange(len(table.lines)) / data.sample_rate
    )
    q = _matrix(table, cols, "q", path, n)
    qd = _matrix(table, cols, "qd", path, n) if cols.qd else None
    qdd = _matrix(table, cols, "qdd", path, n) if cols.qdd else None
    if cols.tau:
        tau = _matrix(table, cols, "tau", path, n)
    else:
        if data.torque_constants is None:
            raise ExciteError("data.torque_constants", f"give one torque constant [Nm/A] per active joint ({n})")
        tau = _matrix(table, cols, "current", path, n) * np.asarray(data.torque_constants)
    signals = {
        name: x
        for name, x in (("time", time[:, None]), ("q", q), ("qd", qd), ("qdd", qdd), ("tau", tau))
        if x is not None
    }
    ok, issue = _usable(time, signals)
    if issue and not drop:
        raise ExciteError("data", f"{path.name}: {issue} (data.bad_rows: drop leaves such rows out)")
    if data.angle_unit == "deg":
        q, qd, qdd = (None if x is None else np.deg2rad(x) for x in (q, qd, qdd))
    if data.signs is not None:
        s = np.asarray(data.signs, dtype=float)
        q, qd, qdd, tau = (None if x is None else x * s for x in (q, qd, qdd, tau))
    if data.motor_side:  # motor angles m = R q and motor torques: to the joints, q = R⁻¹ m and τ = Rᵀ τ_m
        R = data.transmission.reduction()
        inverse = np.linalg.inv(R)
        q, qd, qdd = (None if x is None else x @ inverse.T for x in (q, qd, qdd))
        tau = tau @ R
    keep = ok if run.crop is None else ok & (time >= run.crop[0]) & (time <= run.crop[1])
    if keep.sum() < 2 and run.crop is None:
        raise ExciteError("data", f"{path.name} has fewer than 2 usable rows")
    if keep.sum() < 2:
        raise ExciteError(
            "data.runs.crop", f"{run.crop} leaves no samples of {path.name} ({time[0]:g} to {time[-1]:g} s)"
        )
    qd, qdd = (None if x is None else x[keep] for x in (qd, qdd))
    return Run(path.name, run.role, time[keep], q[keep], qd, qdd, tau[keep], table.dropped + int((~ok).sum()))
