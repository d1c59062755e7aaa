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
| position_2 | sin 2q, cos 2q | gs2, gc2 [Nm]: second harmonic of a position-dependent torque (cogging, cables) |
| viscous_asymmetric | abs(q̇) | Fva [Nm·s/rad]: viscous Fv + Fva forward, Fv − Fva backward |
| held | 1(abs(q̇) < v_h) · s_last | Fh [Nm]: held (static) friction, s_last the sign of the last motion faster than v_h |
| load_coulomb | abs(τ_rigid) tanh(q̇/v_c) | Fl [–]: Coulomb friction growing with the transmitted load |

v_c (a smooth sign, default 0.01 rad/s), v_s (Stribeck velocity, 0.1 rad/s) and v_h (held
velocity, 0.02 rad/s) are fixed. Direction-dependent Coulomb and Stribeck refine Coulomb friction,
direction-dependent viscous refines viscous: they are candidates for a joint only once the effect
they refine is in its model (``REQUIRES``). Held friction depends on the motion's history (the
samples must be in time order). Load-dependent Coulomb friction is two-stage: τ_rigid is the
rigid-body prediction of a first fit (geared joints whose friction grows with the gear load).
(Friction models: Armstrong-Hélouvry, Dupont, Canudas de Wit, Automatica 1994; load-dependent
friction: Hamon, Gautier, Garrec, IROS 2011.)
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
    "position_2": ("gs2", "gc2"),
    "viscous_asymmetric": ("Fva",),
    "held": ("Fh",),
    "load_coulomb": ("Fl",),
}
REQUIRES = {"coulomb_asymmetric": "coulomb", "stribeck": "coulomb", "viscous_asymmetric": "viscous"}
#: Effects whose columns need the rigid-body torque of a first fit.
TWO_STAGE = ("load_coulomb",)
UNITS = {"Fc": "Nm", "Fa": "Nm", "Fv": "Nm·s/rad", "Fs": "Nm", "tau0": "Nm", "Ia": "kg·m²", "k": "Nm/rad",
         "gs": "Nm", "gc": "Nm", "gs2": "Nm", "gc2": "Nm", "Fva": "Nm·s/rad", "Fh": "Nm", "Fl": "Nm/Nm"}


def held_sign(qd: np.ndarray, held_velocity: float) -> np.ndarray:
    """(T,) 1(abs(q̇) < v_h) · sign of the last sample (in time order) with abs(q̇) ≥ v_h (0 before any)."""
    moving = np.abs(qd) >= held_velocity
    last = np.maximum.accumulate(np.where(moving, np.arange(qd.size), -1))
    return np.where(~moving & (last >= 0), np.sign(qd[np.maximum(last, 0)]), 0.0)


def effect_columns(effect: str, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, coulomb_velocity: float,
                   stribeck_velocity: float, held_velocity: float = 0.02, rigid: np.ndarray | None = None) -> np.ndarray:
    """Columns (T, k) of ``effect`` for one joint's samples q, q̇, q̈ (T,) [rad, rad/s, rad/s²] in time
    order; ``rigid`` (T,) [Nm] the joint's rigid-body torque, needed by ``load_coulomb`` only.

    Raises:
        KeyError: unknown effect.
        ValueError: ``load_coulomb`` without ``rigid``.
    """
    if effect in TWO_STAGE and rigid is None:
        raise ValueError(f"{effect} needs the rigid-body torque")
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
        "position_2": lambda: [np.sin(2.0 * q), np.cos(2.0 * q)],
        "viscous_asymmetric": lambda: [np.abs(qd)],
        "held": lambda: [held_sign(qd, held_velocity)],
        "load_coulomb": lambda: [np.abs(rigid) * sign],
    }[effect]()
    return np.column_stack(columns)
