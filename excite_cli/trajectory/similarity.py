"""How alike two joint trajectories are: the correlation of their mean-removed joint positions.

For trajectories q, p sampled at the same instants, (T, n) [rad], with each joint's mean over time
removed (q̃ = q − q̄, p̃ = p − p̄),

    ρ(q, p) = Σ_t,j q̃_tj p̃_tj / √(Σ q̃² · Σ p̃²)   ∈ [−1, 1],

the cosine of the angle between the two motions as vectors of all joints' samples. ρ = 1: the same
motion (up to amplitude), so running it again adds rows C₀ already has (Eq. 41 stacks them: cond(C)
is unchanged and the excitation grows only as √2); a sequential iteration is new when its largest
ρ with every earlier iteration is well below 1.
"""

from __future__ import annotations

import numpy as np


def correlation(q: np.ndarray, p: np.ndarray) -> float:
    """ρ (module docstring) of two sampled trajectories q, p (T, n) [rad]; 0 when either does not move.

    Raises:
        ValueError: shapes that differ.
    """
    if q.shape != p.shape:
        raise ValueError(f"trajectories of different shapes: {q.shape=} but {p.shape=}")
    a, b = q - q.mean(axis=0), p - p.mean(axis=0)
    norm = float(np.sqrt((a * a).sum() * (b * b).sum()))
    return float((a * b).sum() / norm) if norm > 0.0 else 0.0
