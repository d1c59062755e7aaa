"""Prior data C₀ for the sequential generation (Eq. 41): the regressor rows of an earlier result or of
measured data (an identify report, weighed as identification weighs it), stacked above the new
trajectory's, in this design's columns (base parameters by name, then the same effect columns)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.errors import ExciteError
from excite_cli.h5 import open_h5, read_strings
from excite_cli.stored.design_model import MeasuredPrior
from excite_cli.stored.report import StoredReport, report_in


@dataclass(frozen=True)
class PriorFile:
    """The prior data of ``sequence.prior`` as stored (read once: :func:`read_prior_file`).

    Attributes:
        path: the file.
        rows: (m, b) base-regressor rows: every iteration's of an excite result, stacked, or the file's
            ``/regressor``; None: neither is in the file.
        base_names: (b,) their base-parameter names (``/robot/base_parameter_names``), or None.
        effect_names: the effect columns among ``rows``' (``/robot/effect_names`` of a result), or None.
        effect_columns: (m, e') an identify report's ``/effect_regressor``, or None; effect_column_names:
            its (e',) names.
        report: the identify report the file is (:func:`~excite_cli.stored.report.read_report`), or None.
        predicted: (m,) an identify report's ``/predicted_torque``, the reported model's torque of each
            row [Nm], or None (not an identify report, or one of an earlier version).
    """

    path: Path
    rows: np.ndarray | None
    base_names: list[str] | None
    effect_names: list[str] | None
    effect_columns: np.ndarray | None
    effect_column_names: list[str]
    report: StoredReport | None
    predicted: np.ndarray | None = None


def read_prior_file(path: Path, field: str = "sequence.prior") -> PriorFile:
    """The file at ``path`` opened once: its prior rows and, when it is one, its identify report.

    Raises:
        FileNotFound, ExciteError: (``field``) no readable HDF5 file; a damaged report (:func:`report_in`).
    """
    with open_h5(path, field) as f:
        rows = None
        if "iterations" in f:
            rows = [f["iterations"][k]["regressor"][()] for k in sorted(f["iterations"].keys(), key=int)]
        elif "regressor" in f:
            rows = [np.asarray(f["regressor"][()], dtype=float)]
        has_columns = "effect_regressor" in f
        return PriorFile(
            path,
            None if rows is None else np.vstack(rows) if rows else np.zeros((0, 0)),
            read_strings(f["robot"], "base_parameter_names") if "robot/base_parameter_names" in f else None,
            read_strings(f["robot"], "effect_names") if "robot/effect_names" in f else None,
            np.asarray(f["effect_regressor"][()], dtype=float) if has_columns else None,
            [str(n) for n in f["effect_regressor"].attrs.get("names", [])] if has_columns else [],
            report_in(f, path, field),
            np.asarray(f["predicted_torque"][()], dtype=float) if "predicted_torque" in f else None,
        )


def prior_rows(
    stored: PriorFile,
    base: BaseParameters,
    effect_names: Sequence[str] = (),
    measured: MeasuredPrior | None = None,
    cost_period: float = 1.0,
) -> np.ndarray:
    """Prior data C₀ (m, b+e) for Eq. 41 from an excite result (all iterations' regressors stacked) or
    an HDF5 file with a dataset ``regressor`` of base-regressor rows, then the e effect columns
    ``effect_names`` of the design (``/robot/effect_names`` of a result: the same, in the same order;
    an identify report's ``/effect_regressor``: those it holds, taken by name).

    An identify report's rows (``measured``, see
    :class:`~excite_cli.stored.design_model.MeasuredPrior`) are weighed by their noise: each row times
    σ̄/√(a_j² + ρ_j² τ̂²), the noise the report measured at the row's predicted torque τ̂
    (:meth:`~excite_cli.stored.design_model.MeasuredPrior.row_weights`; σ̄/σ_j, the joint's validation
    error, for a report without a noise table or predicted torques), and every row times
    √(1 / (cost_period · rate)) so that one second of recording carries the information of one second
    of a trajectory on the cost grid (``cost_period`` [s]).

    Raises:
        ExciteError: no regressor in the file, base parameters or effect columns that differ, a report's
            damaged predicted torques.
    """
    path, names, effects = stored.path, stored.base_names, stored.effect_names
    if stored.rows is None:
        raise ExciteError("sequence.prior", f"{path} has neither /iterations nor /regressor")
    empty = stored.rows.shape == (0, 0)  # a result without iterations
    prior = np.zeros((0, base.count + len(effect_names))) if empty else stored.rows
    if effect_names and stored.effect_columns is not None:  # an identify report's effect columns, by name
        prior = np.hstack([prior, _report_effects(stored, effect_names, len(prior))])
        effects = list(effect_names)
    columns = base.count + len(effect_names)
    if (effects is not None and list(effects) != list(effect_names)) or (effects is None and names and effect_names):
        raise ExciteError(
            "sequence.prior",
            f"{path} has the effect columns [{', '.join(effects or [])}]; this design has "
            f"[{', '.join(effect_names)}] (the same effects, or a prior without effects for a design without)",
        )
    if prior.ndim != 2 or prior.shape[1] != columns:
        shape = "x".join(str(n) for n in prior.shape)
        raise ExciteError(
            "sequence.prior",
            f"{path} has regressor rows of shape {shape}; the problem's robot needs (rows, {columns}), one "
            f"column per base parameter{' and effect' if effect_names else ''} (prior data of another robot or "
            "joint set?)",
        )
    if not np.all(np.isfinite(prior)):
        raise ExciteError("sequence.prior", f"{path} contains NaN or infinite values")
    if measured is not None:
        n = len(measured.joints)
        if len(prior) % n:
            raise ExciteError(
                "sequence.prior",
                f"{path} has {len(prior)} regressor rows, not a whole number of instants of its {n} joints",
            )
        predicted = stored.predicted
        if predicted is not None and (predicted.shape != (len(prior),) or not np.all(np.isfinite(predicted))):
            raise ExciteError(
                "sequence.prior",
                f"{path}: /predicted_torque must hold a finite torque for each of its {len(prior)} regressor rows "
                "(damaged?)",
            )
        per_joint = np.tile(measured.weights(), len(prior) // n)  # a report without predicted torques
        weights = per_joint if predicted is None else measured.row_weights(predicted)
        prior = prior * (weights * measured.time_scale(cost_period))[:, None]
    if names is None:
        return prior
    order = np.concatenate(
        [base.column_order(names, "sequence.prior", path), base.count + np.arange(len(effect_names))]
    )
    return prior[:, order]


def _report_effects(stored: PriorFile, effect_names: Sequence[str], rows: int) -> np.ndarray:
    """The columns ``effect_names`` of an identify report's ``/effect_regressor`` (M, e), by its names;
    M must be ``rows``, the report's ``/regressor`` rows.

    Raises:
        ExciteError: a design effect the report did not identify, or a dataset of another shape.
    """
    path, held, columns = stored.path, stored.effect_column_names, stored.effect_columns
    missing = [name for name in effect_names if name not in held]
    if missing:
        raise ExciteError(
            "sequence.prior",
            f"{path} holds the effect columns [{', '.join(held)}], not this design's {', '.join(missing)} (design "
            "for the report's own effects, effects.model, or leave those effects out)",
        )
    if columns.shape != (rows, len(held)):
        shape = "x".join(str(n) for n in columns.shape)
        raise ExciteError(
            "sequence.prior",
            f"{path} has /effect_regressor of shape {shape}; its /regressor and names need ({rows}, {len(held)})",
        )
    return columns[:, [held.index(name) for name in effect_names]]
