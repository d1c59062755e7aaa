"""Candidate effects the rigid-body model lacks: each a block of extra regressor columns for one joint,
linear in its coefficients (τ_j += Σ c_k f_k(q_j, q̇_j, q̈_j)).

| effect | columns f_k | coefficients |
|---|---|---|
| coulomb | tanh(q̇/v_c) | Fc [Nm] |
| coulomb_asymmetric | abs(tanh(q̇/v_c)) | Fa [Nm]: levels Fc + Fa moving forward, Fc − Fa backward |
| viscous | q̇ | Fv [Nm·s/rad] |
| viscous_asymmetric | abs(q̇) | Fva [Nm·s/rad]: viscous Fv + Fva forward, Fv − Fva backward |
| stribeck | tanh(q̇/v_c) exp(−(q̇/v_s)²) | Fs [Nm], v_s searched |
| held | 1(abs(q̇) < v_h) · s_last | Fh [Nm]: held (static) friction, v_h searched |
| load_coulomb | abs(τ_rigid) tanh(q̇/v_c) | Fl [Nm/Nm]: Coulomb friction growing with the transmitted load |
| offset | 1 on the rows of run r, one column per fitted run | τ0 [Nm] per run |
| armature | q̈ | Ia [kg·m²] |
| spring | q | k [Nm/rad] |
| gravity_compensator | sin q, cos q | gs, gc [Nm]: first harmonic of a position-dependent torque |
| position_2 | sin 2q, cos 2q | gs2, gc2 [Nm]: second harmonic (cogging, cables) |

v_c (a smooth sign, 0.01 rad/s) is fixed. The position-dependent effects (``POSITION``) are
guarded: outside the q range the fit data covered they hold their value at its nearer end instead
of extrapolating a spring or a harmonic fitted to a narrower motion. Stribeck and held friction are nonlinear in a shape
parameter, their velocity: each is a family of candidates, one per value of a log-spaced grid
(``SHAPE_GRID``), and the selection keeps at most one member per joint, the one the
cross-validated error prefers (a profile search over the shape, scored on the fit data only).
Direction-dependent Coulomb and Stribeck refine Coulomb friction, direction-dependent viscous
refines viscous: they are candidates for a joint only once the effect they refine is in its model
(``REQUIRES``). Held friction depends on the motion's history (the samples must be in time order):
s_last is the sign of the last motion faster than v_h, so after a reversal the friction keeps its
old sign until the joint really moves (presliding, stiction). Load-dependent Coulomb friction is
two-stage: τ_rigid is the rigid-body prediction of a first fit (geared joints whose friction grows
with the gear load). An offset is one constant per fitted run (a torque sensor or current
amplifier is zeroed per run); a run the fit never saw gets the mean of the fitted runs' offsets.
(Friction models: Armstrong-Hélouvry, Dupont, Canudas de Wit, Automatica 1994; load-dependent
friction: Hamon, Gautier, Garrec, IROS 2011.)
"""

from __future__ import annotations

from typing import NamedTuple, Optional

import numpy as np

COEFFICIENTS = {
    "coulomb": ("Fc",),
    "coulomb_asymmetric": ("Fa",),
    "viscous": ("Fv",),
    "viscous_asymmetric": ("Fva",),
    "stribeck": ("Fs",),
    "held": ("Fh",),
    "load_coulomb": ("Fl",),
    "offset": ("tau0",),
    "armature": ("Ia",),
    "spring": ("k",),
    "gravity_compensator": ("gs", "gc"),
    "position_2": ("gs2", "gc2"),
}
EFFECT_NAMES = tuple(COEFFICIENTS)
REQUIRES = {"coulomb_asymmetric": "coulomb", "stribeck": "coulomb", "viscous_asymmetric": "viscous"}
#: Effects whose columns need the rigid-body torque of a first fit.
TWO_STAGE = ("load_coulomb",)
#: Effects with one column per fitted run.
PER_RUN = ("offset",)
#: Effects nonlinear in a velocity [rad/s], and the name of that velocity.
SHAPES = {"stribeck": "v_s", "held": "v_h"}
#: The config field (identification and simulation) that gives each shape velocity [rad/s].
SHAPE_FIELDS = {"stribeck": "stribeck_velocity", "held": "held_velocity"}
#: Default grid of a shape velocity [rad/s]: factors of 2 to 2.5 from 0.02 to 0.5 rad/s.
SHAPE_GRID = (0.02, 0.05, 0.1, 0.2, 0.5)
#: Effects whose columns depend on the position (they extrapolate to positions the fit never saw).
POSITION = ("spring", "gravity_compensator", "position_2")
UNITS = {
    "Fc": "Nm",
    "Fa": "Nm",
    "Fv": "Nm·s/rad",
    "Fva": "Nm·s/rad",
    "Fs": "Nm",
    "Fh": "Nm",
    "Fl": "Nm/Nm",
    "tau0": "Nm",
    "Ia": "kg·m²",
    "k": "Nm/rad",
    "gs": "Nm",
    "gc": "Nm",
    "gs2": "Nm",
    "gc2": "Nm",
}


class Term(NamedTuple):
    """One effect on one joint: a block of columns of the model.

    Attributes:
        effect: a key of ``COEFFICIENTS``.
        joint: active joint index.
        shape: the shape velocity [rad/s] of a ``SHAPES`` effect (Stribeck v_s, held v_h), else None.
    """

    effect: str
    joint: int
    shape: Optional[float] = None

    def label(self, joints: list[str]) -> str:
        """e.g. ``held panda_joint7 (v_h 0.1 rad/s)``."""
        return f"{self.effect} {joints[self.joint]}" + (
            f" ({SHAPES[self.effect]} {self.shape:g} rad/s)" if self.shape else ""
        )


def held_sign(qd: np.ndarray, held_velocity: float) -> np.ndarray:
    """(T,) 1(abs(q̇) < v_h) · sign of the last sample (in time order) with abs(q̇) ≥ v_h (0 before any)."""
    moving = np.abs(qd) >= held_velocity
    last = np.maximum.accumulate(np.where(moving, np.arange(qd.size), -1))
    return np.where(~moving & (last >= 0), np.sign(qd[np.maximum(last, 0)]), 0.0)


def effect_columns(
    effect: str,
    q: np.ndarray,
    qd: np.ndarray,
    qdd: np.ndarray,
    coulomb_velocity: float,
    shape: float | None = None,
    rigid: np.ndarray | None = None,
    q_range: tuple[float, float] | None = None,
) -> np.ndarray:
    """Columns (T, k) of ``effect`` for one joint's samples q, q̇, q̈ (T,) [rad, rad/s, rad/s²] in time
    order, for one run (an offset is a single column of ones here: the dataset spreads it per run).

    Args:
        coulomb_velocity: v_c of the smooth sign [rad/s].
        shape: the shape velocity [rad/s] of a ``SHAPES`` effect (Stribeck v_s, held v_h).
        rigid: (T,) the joint's rigid-body torque [Nm], needed by ``load_coulomb`` only.
        q_range: (lo, hi) [rad], the joint's q range over the fit data: a ``POSITION`` effect's
            columns are evaluated at q clipped to it (held at their value at the nearer end, the
            guard against extrapolating to positions the fit never saw); None: no guard.

    Raises:
        KeyError: unknown effect.
        ValueError: ``load_coulomb`` without ``rigid``, a ``SHAPES`` effect without its shape.
    """
    if effect in TWO_STAGE and rigid is None:
        raise ValueError(f"{effect} needs the rigid-body torque")
    if effect in SHAPES and not shape:
        raise ValueError(f"{effect} needs its shape velocity {SHAPES[effect]}")
    if effect in POSITION and q_range is not None:
        q = np.clip(q, *q_range)
    sign = np.tanh(qd / coulomb_velocity)
    columns = {
        "coulomb": lambda: [sign],
        "coulomb_asymmetric": lambda: [np.abs(sign)],
        "viscous": lambda: [qd],
        "viscous_asymmetric": lambda: [np.abs(qd)],
        "stribeck": lambda: [sign * np.exp(-((qd / shape) ** 2))],
        "held": lambda: [held_sign(qd, shape)],
        "load_coulomb": lambda: [np.abs(rigid) * sign],
        "offset": lambda: [np.ones_like(q)],
        "armature": lambda: [qdd],
        "spring": lambda: [q],
        "gravity_compensator": lambda: [np.sin(q), np.cos(q)],
        "position_2": lambda: [np.sin(2.0 * q), np.cos(2.0 * q)],
    }[effect]()
    return np.column_stack(columns)


def coefficient_names(term: Term, offset_runs: list[str]) -> list[str]:
    """Names of a term's coefficients: those of ``COEFFICIENTS``, an offset per run as
    ``tau0[run label]`` when the fit has several runs (``offset_runs``)."""
    names = COEFFICIENTS[term.effect]
    if term.effect in PER_RUN and len(offset_runs) > 1:
        return [f"{names[0]}[{label}]" for label in offset_runs]
    return list(names)
