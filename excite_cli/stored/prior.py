"""Prior data C₀ for the sequential generation (Eq. 41): the regressor rows of an earlier result or of
measured data (an identify report, weighed as identification weighs it), stacked above the new
trajectory's, in this design's columns (base parameters by name, then the same effect columns)."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.errors import ExciteError
from excite_cli.h5 import open_h5, read_strings
from excite_cli.stored.design_model import MeasuredPrior


def read_prior(
    path: Path,
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
    :class:`~excite_cli.stored.design_model.MeasuredPrior`) are weighed as
    identification weighs them: each joint's rows times σ̄/σ_j, and every row times
    √(1 / (cost_period · rate)) so that one second of recording carries the information of one second
    of a trajectory on the cost grid (``cost_period`` [s]).

    Raises:
        ExciteError: missing or unreadable file, no regressor inside, or base parameters or effect
            columns that differ.
    """
    with open_h5(path, "sequence.prior") as f:
        if "iterations" in f:
            keys = sorted(f["iterations"].keys(), key=int)
            blocks = [f["iterations"][k]["regressor"][()] for k in keys]
            prior = np.vstack(blocks) if blocks else np.zeros((0, base.count + len(effect_names)))
        elif "regressor" in f:
            prior = np.asarray(f["regressor"][()], dtype=float)
        else:
            raise ExciteError("sequence.prior", f"{path} has neither /iterations nor /regressor")
        names = read_strings(f["robot"], "base_parameter_names") if "robot/base_parameter_names" in f else None
        effects = read_strings(f["robot"], "effect_names") if "robot/effect_names" in f else None
        if effect_names and "effect_regressor" in f:  # an identify report's effect columns, taken by name
            prior = np.hstack([prior, _report_effects(f["effect_regressor"], effect_names, path, len(prior))])
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
        weights = measured.weights() * measured.time_scale(cost_period)
        if len(prior) % weights.size:
            raise ExciteError(
                "sequence.prior",
                f"{path} has {len(prior)} regressor rows, not a whole number of instants of its {weights.size} joints",
            )
        prior = (prior.reshape(-1, weights.size, prior.shape[1]) * weights[None, :, None]).reshape(prior.shape)
    if names is None:
        return prior
    order = np.concatenate(
        [base.column_order(names, "sequence.prior", path), base.count + np.arange(len(effect_names))]
    )
    return prior[:, order]


def _report_effects(dataset, effect_names: Sequence[str], path: Path, rows: int) -> np.ndarray:
    """The columns ``effect_names`` of an identify report's ``/effect_regressor`` (M, e), by its names;
    M must be ``rows``, the report's ``/regressor`` rows.

    Raises:
        ExciteError: a design effect the report did not identify, or a dataset of another shape.
    """
    held = [str(name) for name in dataset.attrs.get("names", [])]
    missing = [name for name in effect_names if name not in held]
    if missing:
        raise ExciteError(
            "sequence.prior",
            f"{path} holds the effect columns [{', '.join(held)}], not this design's {', '.join(missing)} (design "
            "for the report's own effects, effects.model, or leave those effects out)",
        )
    columns = np.asarray(dataset[()], dtype=float)
    if columns.shape != (rows, len(held)):
        shape = "x".join(str(n) for n in columns.shape)
        raise ExciteError(
            "sequence.prior",
            f"{path} has /effect_regressor of shape {shape}; its /regressor and names need ({rows}, {len(held)})",
        )
    return columns[:, [held.index(name) for name in effect_names]]
