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
from excite_cli.identification.config import ColumnsConfig, DataConfig, RunConfig
from excite_cli.identification.measured.bags import bag_columns, is_bag, read_bag
from excite_cli.identification.measured.files import Table, read_table


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


def _matrix(table: Table, keys: list, field: str, path: Path, n: int) -> np.ndarray:
    if len(keys) != n:
        raise ExciteError(f"data.columns.{field}", f"{len(keys)} columns for the robot's {n} active joints")
    return np.column_stack([table.column(key, field, path) for key in keys])


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
    path = resolve_path(run.file, folder)
    n = len(joints)
    if not path.exists():
        raise FileNotFound("data.runs", path)
    drop = data.bad_rows == "drop"
    if is_bag(path):
        table = read_bag(path, data.topic, joints)
        cols = data.columns or ColumnsConfig(**bag_columns(joints, table))
    elif path.is_dir():
        raise ExciteError("data.runs", f"{path} is a folder, not a data file or a ROS 2 bag", path)
    elif data.columns is None:
        raise ExciteError(
            "data.columns", f"is required for {path.name} (only a ROS bag's columns follow the joint names)"
        )
    else:
        table, cols = read_table(path, drop), data.columns
    time = table.column(cols.time, "time", path)
    q = _matrix(table, cols.q, "q", path, n)
    qd = _matrix(table, cols.qd, "qd", path, n) if cols.qd else None
    qdd = _matrix(table, cols.qdd, "qdd", path, n) if cols.qdd else None
    if cols.tau:
        tau = _matrix(table, cols.tau, "tau", path, n)
    else:
        if data.torque_constants is None or len(data.torque_constants) != n:
            raise ExciteError("data.torque_constants", f"give one torque constant [Nm/A] per active joint ({n})")
        if not np.all(np.isfinite(data.torque_constants)):
            raise ExciteError("data.torque_constants", "every torque constant must be a finite number [Nm/A]")
        tau = _matrix(table, cols.current, "current", path, n) * np.asarray(data.torque_constants)
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
        if len(data.signs) != n:
            raise ExciteError("data.signs", f"{len(data.signs)} signs for {n} active joints")
        s = np.asarray(data.signs, dtype=float)
        q, qd, qdd, tau = (None if x is None else x * s for x in (q, qd, qdd, tau))
    keep = ok if run.crop is None else ok & (time >= run.crop[0]) & (time <= run.crop[1])
    if keep.sum() < 2 and run.crop is None:
        raise ExciteError("data", f"{path.name} has fewer than 2 usable rows")
    if keep.sum() < 2:
        raise ExciteError(
            "data.runs.crop", f"{run.crop} leaves no samples of {path.name} ({time[0]:g} to {time[-1]:g} s)"
        )
    qd, qdd = (None if x is None else x[keep] for x in (qd, qdd))
    return Run(path.name, run.role, time[keep], q[keep], qd, qdd, tau[keep], table.dropped + int((~ok).sum()))
