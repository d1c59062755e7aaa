"""Smooth maximum (log-sum-exp) that aggregates sampled inequalities s_t ≤ 0 into one.

g = (1/β) log Σ exp(β s) + δ never under-estimates max s + δ and over-estimates it by at most
log(count)/β. SQP iterates approach g = 0 from outside, so a constraint accepts a point when its
exact samples keep δ/2 (``ACCEPT_MARGIN``), which also covers the overshoot between grid instants.
"""

from __future__ import annotations

import numpy as np

#: β, in the normalized units of each constraint.
SHARPNESS = 300.0
#: δ, normalized.
GRID_MARGIN = 0.01
#: What the exact grid samples must keep for acceptance, normalized.
ACCEPT_MARGIN = GRID_MARGIN / 2.0


def smooth_max(values: np.ndarray, axis: int | tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Aggregate g over ``axis`` of ``values`` and the weights ∂g/∂values (shaped like ``values``).

    g = (m + log Σ exp(β s − m))/β + δ with m the largest β s (the usual shift that keeps every
    exponential ≤ 1), and the weights exp(β s − m)/Σ (the softmax), from the same exponentials.
    """
    peak, exponentials, total = _shifted(values, axis)
    return _aggregate(peak, total, axis), exponentials / total


def smooth_max_value(values: np.ndarray, axis: int | tuple[int, ...]) -> np.ndarray:
    """The aggregated g of :func:`smooth_max` alone (a line search's trial points need no weights)."""
    peak, _, total = _shifted(values, axis)
    return _aggregate(peak, total, axis)


def _shifted(values: np.ndarray, axis: int | tuple[int, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """m = max β s over ``axis`` (0 where not finite), exp(β s − m) and their sum, dimensions kept."""
    scaled = SHARPNESS * values
    peak = np.max(scaled, axis=axis, keepdims=True)
    peak[~np.isfinite(peak)] = 0.0
    exponentials = np.exp(scaled - peak)
    return peak, exponentials, np.sum(exponentials, axis=axis, keepdims=True)


def _aggregate(peak: np.ndarray, total: np.ndarray, axis: int | tuple[int, ...]) -> np.ndarray:
    with np.errstate(divide="ignore"):  # no sample at all: log 0 = −inf, no constraint
        return np.squeeze(peak + np.log(total), axis=axis) / SHARPNESS + GRID_MARGIN
