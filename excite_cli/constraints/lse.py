"""Smooth maximum (log-sum-exp) that aggregates sampled inequalities s_t ≤ 0 into one.

g = (1/β) log Σ exp(β s) + δ never under-estimates max s + δ and over-estimates it by at most
log(count)/β. SQP iterates approach g = 0 from outside, so a constraint accepts a point when its
exact samples keep δ/2 (``ACCEPT_MARGIN``), which also covers the overshoot between grid instants.
"""

from __future__ import annotations

import numpy as np
from scipy.special import logsumexp, softmax

#: β, in the normalized units of each constraint.
SHARPNESS = 300.0
#: δ, normalized.
GRID_MARGIN = 0.01
#: What the exact grid samples must keep for acceptance, normalized.
ACCEPT_MARGIN = GRID_MARGIN / 2.0


def smooth_max(values: np.ndarray, axis: int | tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Aggregate g over ``axis`` of ``values`` and the weights ∂g/∂values (shaped like ``values``)."""
    return smooth_max_value(values, axis), softmax(SHARPNESS * values, axis=axis)


def smooth_max_value(values: np.ndarray, axis: int | tuple[int, ...]) -> np.ndarray:
    """The aggregated g of :func:`smooth_max` alone (a line search's trial points need no weights)."""
    return logsumexp(SHARPNESS * values, axis=axis) / SHARPNESS + GRID_MARGIN
