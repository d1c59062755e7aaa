"""Candidate effects the rigid-body model lacks: each a block of extra regressor columns for one joint,
linear in its coefficients (τ_j += Σ c_k f_k(q_j, q̇_j, q̈_j)).

| effect | columns f_k | coefficients |
|---|---|---|
| coulomb | tanh(q̇/v_c) | Fc [Nm] |
| coulomb_asymmetric | abs(tanh(q̇/v_c)) | Fa [Nm]: levels Fc + Fa moving forward, Fc − Fa backward |
| viscous | q̇ | Fv [Nm·s/rad] |
| stribeck | tanh(q̇/v_c) exp(−(q̇/v_s)²) | Fs [Nm] |
| offset | 1 | τ0 [Nm] |
| armature | q̈ | Ia [kg·m²] |
| spring | q | k [Nm/rad] |
| gravity_compensator | sin q, cos q | gs, gc [Nm] |

v_c (a smooth sign, default 0.01 rad/s) and v_s (Stribeck velocity, 0.1 rad/s) are fixed.
Direction-dependent Coulomb and Stribeck refine Coulomb friction: they are candidates for a joint
only once ``coulomb`` is in its model (``REQUIRES``).
(Friction models: Armstrong-Hélouvry, Dupont, Canudas de Wit, Automatica 1994.)
"""

from __future__ import annotations

import numpy as np

COEFFICIENTS = {
    "coulomb": ("Fc",),
    "coulomb_asymmetric": ("Fa",),
    "viscous": ("Fv",),
    "stribeck": ("Fs",),
    "offset": ("tau0",),
    "armature": ("Ia",),
    "spring": ("k",),
    "gravity_compensator": ("gs", "gc"),
}
REQUIRES = {"coulomb_asymmetric": "coulomb", "stribeck": "coulomb"}
UNITS = {"Fc": "Nm", "Fa": "Nm", "Fv": "Nm·s/rad", "Fs": "Nm", "tau0": "Nm", "Ia": "kg·m²", "k": "Nm/rad",
         "gs": "Nm", "gc": "Nm"}


def effect_columns(effect: str, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, coulomb_velocity: float,
                   stribeck_velocity: float) -> np.ndarray:
    """Columns (T, k) of ``effect`` for one joint's samples q, q̇, q̈ (T,) [rad, rad/s, rad/s²].

    Raises:
        KeyError: unknown effect.
    """
    sign = np.tanh(qd / coulomb_velocity)
    columns = {
        "coulomb": lambda: [sign],
        "coulomb_asymmetric": lambda: [np.abs(sign)],
        "viscous": lambda: [qd],
        "stribeck": lambda: [sign * np.exp(-((qd / stribeck_velocity) ** 2))],
        "offset": lambda: [np.ones_like(q)],
        "armature": lambda: [qdd],
        "spring": lambda: [q],
        "gravity_compensator": lambda: [np.sin(q), np.cos(q)],
    }[effect]()
    return np.column_stack(columns)
