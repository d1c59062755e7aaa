"""An identify report read back: the one reader of the model a report holds, for ``validate`` (its
model scored on other runs), ``effects.model`` (the next design's effects) and ``sequence.prior`` (how
its measured rows weigh). The file is opened once and every field a user of it takes is checked,
its errors named under the field that gave the path."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from excite_cli.config import COULOMB_VELOCITY
from excite_cli.effects import EFFECTS
from excite_cli.errors import ExciteError
from excite_cli.h5 import open_h5, read_strings

#: A stored term: (effect, joint name, shape velocity [rad/s] or None, coupling (n,) or None).
StoredTerm = tuple[str, str, Optional[float], Optional[tuple[float, ...]]]


@dataclass(frozen=True)
class StoredReport:
    """The model of an identify report (the fit it reports: least squares or consistent) and what
    weighs its rows as prior data.

    Attributes:
        joints: (n,) active joint names; base_names: (b,) base-parameter names.
        base: (b,) base parameters [SI]; rigid: (b,) the rigid-body-only fit's (for load-dependent terms).
        terms: every effect of its model, in order (a coupled motor once).
        coefficients: effect coefficients, in the order of ``terms``' columns [SI].
        offset_runs: offset columns (one per fitted run, at least 1).
        cutoff: low-pass cut-off [Hz]; coulomb_velocity: v_c of the smooth sign(q̇) [rad/s].
        q_range: (n, 2) [rad] the fit data's q range per joint that guards the position effects
            (None: a report from before the guard).
        rms_after: (n,) [Nm] each joint's RMS error of the reported model on the validation data
            (``/identification/rms_after``), or None (a report of an earlier excite).
        rate: its rows' sample rate [Hz] (``/regressor`` attribute ``sample_rate_Hz``), or None (the same).
        noise_level: (n, 3) each joint's fitted noise (a [Nm], ρ [1], a's 95 % upper bound [Nm]) of its
            rows, at the report's rate (``/identification/noise_level`` times √ of its ``noise_gain``; a
            table without ``absolute_upper``: a), NaN for a dead channel, or None (a report of an earlier
            excite, or fit data too short to fit it).
        rotors: the last ``rotors`` of ``terms`` are the consistent fit's rotors with columns of their own
            (armature the effect search did not choose:
            :mod:`~excite_cli.identification.choice.consistent_model`), part of what it predicts.
    """

    joints: list[str]
    base_names: list[str]
    base: np.ndarray
    rigid: np.ndarray
    terms: list[StoredTerm]
    coefficients: np.ndarray
    offset_runs: int
    cutoff: float
    coulomb_velocity: float
    q_range: np.ndarray | None = None
    rms_after: np.ndarray | None = None
    rate: float | None = None
    rotors: int = 0
    noise_level: np.ndarray | None = None


def read_report(path: Path, field: str) -> StoredReport | None:
    """The identify report at ``path``, or None for an HDF5 file that is not one (no /identification:
    an optimize result, a file of regressor rows).

    Args:
        field: the config field or argument that named ``path`` (``report``, ``effects.model``,
            ``sequence.prior``), under which every error is raised.

    Raises:
        FileNotFound, ExciteError: no readable HDF5 file; a report without its effects table or
            one of its fields, a dataset of another shape than its joints and base parameters give or
            not finite, a cut-off or Coulomb velocity scale that is not a positive number.
    """
    with open_h5(path, field) as f:
        return report_in(f, path, field)


def report_in(f, path: Path, field: str) -> StoredReport | None:
    """:func:`read_report` of the open HDF5 file ``f`` (read from ``path``), for a reader that takes
    more of the same file in the same opening.

    Raises:
        ExciteError: as :func:`read_report`.
    """
    if "identification" not in f:
        return None
    g = f["identification"]
    if "effects" not in g:
        raise ExciteError(field, f"{path} is not an identify report (no /identification/effects)")
    for name, unit in (("cutoff_Hz", "Hz"), ("coulomb_velocity_rad_s", "rad/s")):
        value = float(g.attrs.get(name, COULOMB_VELOCITY))
        if not (np.isfinite(value) and value > 0.0):  # checked like the config field it came from
            raise ExciteError(field, f"{path}: /identification {name} is {value:g}", value, f"> 0 {unit}")
    joints, names = read_strings(g, "joint_names"), read_strings(g, "base_parameter_names")
    rows = g["effects"][()]
    for column in ("effect", "joint", "value"):
        if rows.dtype.names is None or column not in rows.dtype.names:
            raise ExciteError(field, f"{path}: /identification/effects has no field '{column}' (damaged?)")
    consistent = bool(g["physically_consistent"][()]) if "physically_consistent" in g else False
    values = rows["value_consistent"] if consistent and "value_consistent" in rows.dtype.names else rows["value"]
    checked = _Checked(g, path, field)
    coupling = checked("effect_coupling", (len(rows), len(joints))) if "effect_coupling" in g else None
    rotors, inertias = _own_rotors(g, checked) if consistent else ([], np.zeros(0))
    return StoredReport(
        joints,
        names,
        checked("base_parameters", (len(names),)),
        checked("base_parameters_rigid_only", (len(names),)),
        _known(_terms(rows, coupling) + rotors, joints, path, field),
        checked.finite(np.concatenate([np.asarray(values, dtype=float), inertias]), "effects"),
        max(1, len(g["offset_runs"][()])) if "offset_runs" in g else 1,
        float(g.attrs["cutoff_Hz"]),
        float(g.attrs.get("coulomb_velocity_rad_s", COULOMB_VELOCITY)),
        checked("fit_q_range", (len(joints), 2)) if "fit_q_range" in g else None,
        np.asarray(g["rms_after"][()], dtype=float) if "rms_after" in g else None,
        float(f["regressor"].attrs["sample_rate_Hz"])
        if "regressor" in f and "sample_rate_Hz" in f["regressor"].attrs
        else None,
        len(rotors),
        _noise_level(g, len(joints), path, field),
    )


def _noise_level(g, n: int, path: Path, field: str) -> np.ndarray | None:
    """(n, 3) a [Nm], ρ [1], a's upper bound [Nm] of the report's rows (at its rate: the fit times
    √noise_gain; a for a table without ``absolute_upper``), or None.

    Raises:
        ExciteError: a table without a row per joint or its fields, or a noise gain outside (0, 1].
    """
    if "noise_level" not in g:
        return None
    table = g["noise_level"]
    rows, gain = table[()], float(table.attrs.get("noise_gain", 1.0))
    if rows.dtype.names is None or not {"absolute", "relative"} <= set(rows.dtype.names) or len(rows) != n:
        raise ExciteError(
            field, f"{path}: /identification/noise_level needs a row per joint with absolute and relative"
        )
    if not 0.0 < gain <= 1.0:
        raise ExciteError(field, f"{path}: /identification/noise_level noise_gain is {gain:g}", gain, "0 < gain ≤ 1")
    upper = rows["absolute_upper"] if "absolute_upper" in rows.dtype.names else rows["absolute"]
    return np.column_stack([rows["absolute"], rows["relative"], upper]).astype(float) * np.sqrt(gain)


def _terms(rows: np.ndarray, coupling: np.ndarray | None) -> list[StoredTerm]:
    """The distinct terms of the effects table ``rows`` (a term has a row per coefficient), each with its
    row of ``coupling`` (rows, n) where it is not zero."""
    shapes = rows["shape"] if "shape" in rows.dtype.names else np.full(len(rows), np.nan)
    coupling = np.zeros((len(rows), 1)) if coupling is None else coupling
    terms: list[StoredTerm] = []
    effects, joint_of = ([v.decode() if isinstance(v, bytes) else str(v) for v in rows[c]] for c in ("effect", "joint"))
    for effect, joint, shape, weights in zip(effects, joint_of, shapes, coupling):
        coupled = tuple(float(w) for w in weights) if np.any(weights) else None
        term = (effect, joint, None if np.isnan(shape) else float(shape), coupled)
        if term not in terms:
            terms.append(term)
    return terms


def _own_rotors(g, checked: _Checked) -> tuple[list[StoredTerm], np.ndarray]:
    """The consistent fit's rotors with columns of their own (/identification/``rotor_own_columns``: not
    in its base parameters) as armature terms, and their inertias [kg m²] (none in a report of an
    earlier excite).

    Raises:
        ExciteError: ``rotor_inertias`` or ``rotor_joints`` missing or of another length (damaged).
    """
    if "rotor_own_columns" not in g:
        return [], np.zeros(0)
    own = np.asarray(g["rotor_own_columns"][()], dtype=bool).ravel()
    inertias = checked("rotor_inertias", own.shape)
    joints = read_strings(g, "rotor_joints") if "rotor_joints" in g else []
    if len(joints) != own.size:
        raise ExciteError(
            checked.field, f"{checked.path}: /identification/rotor_joints names {len(joints)} of {own.size} rotors"
        )
    return [("armature", j, None, None) for j, o in zip(joints, own) if o], inertias[own]


def _known(terms: list[StoredTerm], joints: list[str], path: Path, field: str) -> list[StoredTerm]:
    """``terms``, every effect one of :data:`~excite_cli.effects.EFFECTS` and every joint's own term on
    one of the report's ``joints``.

    Raises:
        ExciteError: (``field``) an effect or a joint the report does not define (damaged, or written
            by another version of excite).
    """
    for effect, joint, _, coupling in terms:
        if effect not in EFFECTS:
            raise ExciteError(
                field,
                f"{path}: /identification/effects names the effect '{effect}' (damaged, or from another excite?)",
                effect,
                f"one of {', '.join(EFFECTS)}",
            )
        if coupling is None and joint not in joints:
            raise ExciteError(
                field,
                f"{path}: /identification/effects names the joint '{joint}', not one of its joint_names (damaged?)",
            )
    return terms


@dataclass(frozen=True)
class _Checked:
    """The report's datasets /identification/<name> read as floats, checked (errors under ``field``)."""

    group: object
    path: Path
    field: str

    def __call__(self, name: str, shape: tuple[int, ...]) -> np.ndarray:
        """The dataset ``name`` as floats of ``shape``, every value finite.

        Raises:
            ExciteError: missing, of another shape, or not finite (the dataset named).
        """
        if name not in self.group:
            raise ExciteError(self.field, f"{self.path}: /identification/{name} is missing (damaged?)")
        values = np.asarray(self.group[name][()], dtype=float)
        if values.shape != shape:
            found, wanted = ("x".join(map(str, s)) or "scalar" for s in (values.shape, shape))
            raise ExciteError(self.field, f"{self.path}: /identification/{name} has shape {found}", expected=wanted)
        return self.finite(values, name)

    def finite(self, values: np.ndarray, name: str) -> np.ndarray:
        """``values``, refused where one is NaN or infinite (the dataset named)."""
        if not np.all(np.isfinite(values)):
            raise ExciteError(
                self.field, f"{self.path}: /identification/{name} holds NaN or infinite values (damaged?)"
            )
        return values


def read_identify_report(path: Path, field: str) -> StoredReport:
    """:func:`read_report` of a file that must be an identify report.

    Raises:
        ExciteError: as :func:`read_report`, and a file without /identification (not an identify report).
    """
    return identify_report(read_report(path, field), path, field)


def identify_report(report: StoredReport | None, path: Path, field: str) -> StoredReport:
    """``report`` (read from ``path``), which must be one.

    Raises:
        ExciteError: (``field``) None: the file has no /identification (not an identify report).
    """
    if report is None:
        raise ExciteError(field, f"{path} is not an identify report (no /identification/effects)")
    return report
