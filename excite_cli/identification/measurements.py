"""Measured runs in: CSV with a header or HDF5 datasets, mapped to time, q, (q̇, q̈) and τ (or motor
current × torque constants), in SI units and the robot's sign conventions."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import h5py
import numpy as np

from excite_cli.config import DataConfig, IdentifyProblem, RunConfig
from excite_cli.errors import ExciteError


@dataclass(frozen=True)
class Run:
    """One measured run in SI units.

    Attributes:
        name: file name.
        role: ``fit``, ``validation`` or ``blocks`` (split into alternating time blocks).
        time: (T,) strictly increasing [s].
        q: (T, n) [rad]; qd, qdd: (T, n) [rad/s, rad/s²] or None when to be differentiated.
        tau: (T, n) joint torques [Nm].
    """

    name: str
    role: str
    time: np.ndarray
    q: np.ndarray
    qd: Optional[np.ndarray]
    qdd: Optional[np.ndarray]
    tau: np.ndarray


def _read_table(path: Path) -> dict[str, np.ndarray]:
    """Columns of a CSV (header row) or the 1-D datasets of an HDF5 file, by name."""
    if path.suffix.lower() in (".h5", ".hdf5"):
        with h5py.File(path, "r") as f:
            return {name: np.asarray(f[name][()], dtype=float) for name in f if isinstance(f[name], h5py.Dataset)}
    with path.open() as handle:
        header = handle.readline().strip().split(",")
    try:
        values = np.atleast_2d(np.genfromtxt(path, delimiter=",", skip_header=1, dtype=float))
    except ValueError as exc:
        raise ExciteError(f"data: {path.name}: cannot parse the CSV ({' '.join(str(exc).split())[:200]})") from None
    if values.shape[1] != len(header):
        raise ExciteError(f"data: {path}: {values.shape[1]} values per row but {len(header)} header names")
    return {name.strip(): values[:, k] for k, name in enumerate(header)}


def _matrix(table: dict[str, np.ndarray], names: list[str], field: str, path: Path, n: int) -> np.ndarray:
    if len(names) != n:
        raise ExciteError(f"data.columns.{field}: {len(names)} columns for the robot's {n} active joints")
    missing = [name for name in names if name not in table]
    if missing:
        raise ExciteError(f"data.columns.{field}: {path.name} has no column '{missing[0]}' (it has: {', '.join(list(table)[:12])}, ...)")
    return np.column_stack([table[name] for name in names])


def load_run(run: RunConfig, data: DataConfig, problem: IdentifyProblem, n: int) -> Run:
    """Read, convert and validate one run.

    Args:
        run: the run's entry of ``data.runs``.
        data: the data section (columns, units, gains, signs).
        problem: for resolving the file path.
        n: number of active joints.

    Raises:
        ExciteError: missing file, wrong column count or name, NaN or missing values, time not
            strictly increasing, a crop that leaves nothing.
    """
    path = problem.resolve(run.file)
    if not path.is_file():
        raise ExciteError(f"data.runs: file not found: {path}")
    table = _read_table(path)
    cols = data.columns
    if cols.time not in table:
        raise ExciteError(f"data.columns.time: {path.name} has no column '{cols.time}'")
    time = table[cols.time]
    q = _matrix(table, cols.q, "q", path, n)
    qd = _matrix(table, cols.qd, "qd", path, n) if cols.qd else None
    qdd = _matrix(table, cols.qdd, "qdd", path, n) if cols.qdd else None
    if cols.tau:
        tau = _matrix(table, cols.tau, "tau", path, n)
    else:
        if data.torque_constants is None or len(data.torque_constants) != n:
            raise ExciteError(f"data.torque_constants: give one torque constant [Nm/A] per active joint ({n})")
        tau = _matrix(table, cols.current, "current", path, n) * np.asarray(data.torque_constants)
    for name, values in (("time", time), ("q", q), ("qd", qd), ("qdd", qdd), ("tau", tau)):
        if values is not None and not np.all(np.isfinite(values)):
            row = int(np.nonzero(~np.all(np.isfinite(values.reshape(len(values), -1)), axis=1))[0][0])
            raise ExciteError(f"data: {path.name}: NaN or missing value in {name} at data row {row + 1}")
    if np.any(np.diff(time) <= 0):
        row = int(np.nonzero(np.diff(time) <= 0)[0][0])
        raise ExciteError(f"data: {path.name}: time is not strictly increasing at data row {row + 2} ({time[row + 1]:g} s)")
    if data.angle_unit == "deg":
        q, qd, qdd = (None if x is None else np.deg2rad(x) for x in (q, qd, qdd))
    if data.signs is not None:
        if len(data.signs) != n:
            raise ExciteError(f"data.signs: {len(data.signs)} signs for {n} active joints")
        s = np.asarray(data.signs, dtype=float)
        q, qd, qdd, tau = (None if x is None else x * s for x in (q, qd, qdd, tau))
    keep = np.ones(time.size, dtype=bool) if run.crop is None else (time >= run.crop[0]) & (time <= run.crop[1])
    if keep.sum() < 2:
        raise ExciteError(f"data.runs.crop: {run.crop} leaves no samples of {path.name} ({time[0]:g} to {time[-1]:g} s)")
    pick = (lambda x: None if x is None else x[keep])
    return Run(path.name, run.role, time[keep], q[keep], pick(qd), pick(qdd), tau[keep])
