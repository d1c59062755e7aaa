"""Candidate effects the rigid-body model lacks: each a block of extra regressor columns for one joint,
linear in its coefficients (τ_j += Σ c_k f_k(q_j, q̇_j, q̈_j)).

Each effect is one :class:`Effect` record in ``EFFECTS``: adding an effect is adding a record.
v_c (a smooth sign, 0.01 rad/s) is fixed. The position-dependent effects (``position``) are
guarded: outside the q range the fit data covered they hold their value at its nearer end instead
of extrapolating a spring or a harmonic fitted to a narrower motion. Stribeck and held friction are nonlinear in a shape
parameter, their velocity: each is a family of candidates, one per value of a log-spaced grid
(``SHAPE_GRID``), and the selection keeps at most one member per joint, the one the
cross-validated error prefers (a profile search over the shape, scored on the fit data only).
Direction-dependent Coulomb and Stribeck refine Coulomb friction, direction-dependent viscous
refines viscous: they are candidates for a joint only once the effect they refine is in its model
(``requires``). Held friction depends on the motion's history (the samples must be in time order):
s_last is the sign of the last motion faster than v_h, so after a reversal the friction keeps its
old sign until the joint really moves (presliding, stiction). Load-dependent Coulomb friction is
two-stage: τ_rigid is the rigid-body prediction of a first fit (geared joints whose friction grows
with the gear load). An offset is one constant per fitted run (a torque sensor or current
amplifier is zeroed per run); a run the fit never saw gets the mean of the fitted runs' offsets.
A motor that turns with several joints (a coupled wrist: s = q5 + q6) is one effect, ``motor``: its
rotor inertia, Coulomb and viscous friction in the motor coordinate enter and leave the model
together, as the physical motor has all three.
(Friction models: Armstrong-Hélouvry, Dupont, Canudas de Wit, Automatica 1994; load-dependent
friction: Hamon, Gautier, Garrec, IROS 2011.)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, NamedTuple, Optional

import numpy as np


class Signals(NamedTuple):
    """One joint's samples an effect's columns are made of, in time order (T,) each: q [rad], q̇
    [rad/s], q̈ [rad/s²], the smooth sign tanh(q̇/v_c), the shape velocity of a shaped effect [rad/s]
    and the joint's rigid-body torque [Nm] of a two-stage effect (None where not needed)."""

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    sign: np.ndarray
    shape: Optional[float]
    rigid: Optional[np.ndarray]


@dataclass(frozen=True)
class Effect:
    """One candidate effect, everything about it in one record.

    Attributes:
        name: the name configs and reports use.
        coefficients: its coefficients' names, one per column (an offset: one per fitted run).
        units: their units.
        columns: ``columns(signals)`` → the columns (a list of (T,) arrays) on the joint's own row.
        requires: the effect it refines, which must be in the joint's model first (or None).
        shape: the name of the velocity it is nonlinear in (``v_s``, ``v_h``), searched on a grid;
            shape_field: the config field (identification and simulation) giving that grid [rad/s].
        two_stage: its columns need the rigid-body torque of a first fit.
        per_run: one column per fitted run.
        position: its columns depend on the position, so they are guarded outside the fit data's
            q range.
        motor: a motor's inertia or friction, which acts through a transmission.
        coupled: proposed only on motors that turn with several joints (:class:`Term` ``coupling``),
            never as a joint's own candidate.
    """

    name: str
    coefficients: tuple[str, ...]
    units: tuple[str, ...]
    columns: Callable[[Signals], list[np.ndarray]]
    requires: Optional[str] = None
    shape: Optional[str] = None
    shape_field: Optional[str] = None
    two_stage: bool = False
    per_run: bool = False
    position: bool = False
    motor: bool = False
    coupled: bool = False

    def unit(self, coefficient: str) -> str:
        """The unit of one of its coefficients."""
        return self.units[self.coefficients.index(coefficient)]


#: Every candidate effect, by name (in the order configs and reports list them).
EFFECTS = {
    e.name: e
    for e in (
        Effect("coulomb", ("Fc",), ("Nm",), lambda s: [s.sign], motor=True),
        Effect("coulomb_asymmetric", ("Fa",), ("Nm",), lambda s: [np.abs(s.sign)], requires="coulomb"),
        Effect("viscous", ("Fv",), ("Nm·s/rad",), lambda s: [s.qd], motor=True),
        Effect("viscous_asymmetric", ("Fva",), ("Nm·s/rad",), lambda s: [np.abs(s.qd)], requires="viscous"),
        Effect(
            "stribeck",
            ("Fs",),
            ("Nm",),
            lambda s: [s.sign * np.exp(-((s.qd / s.shape) ** 2))],
            requires="coulomb",
            shape="v_s",
            shape_field="stribeck_velocity",
        ),
        Effect(
            "held", ("Fh",), ("Nm",), lambda s: [held_sign(s.qd, s.shape)], shape="v_h", shape_field="held_velocity"
        ),
        Effect("load_coulomb", ("Fl",), ("Nm/Nm",), lambda s: [np.abs(s.rigid) * s.sign], two_stage=True),
        Effect("offset", ("tau0",), ("Nm",), lambda s: [np.ones_like(s.q)], per_run=True),
        Effect("armature", ("Ia",), ("kg·m²",), lambda s: [s.qdd], motor=True),
        Effect("spring", ("k",), ("Nm/rad",), lambda s: [s.q], position=True),
        Effect("gravity_compensator", ("gs", "gc"), ("Nm", "Nm"), lambda s: [np.sin(s.q), np.cos(s.q)], position=True),
        Effect("position_2", ("gs2", "gc2"), ("Nm", "Nm"), lambda s: [np.sin(2 * s.q), np.cos(2 * s.q)], position=True),
        Effect(
            "motor",
            ("Ia", "Fc", "Fv"),
            ("kg·m²", "Nm", "Nm·s/rad"),
            lambda s: [s.qdd, s.sign, s.qd],
            motor=True,
            coupled=True,
        ),
    )
}
EFFECT_NAMES = tuple(EFFECTS)
#: Coefficients that no physical joint has negative (dry and viscous friction dissipate, a rotor's
#: inertia is a mass distribution's): every fit keeps them ≥ 0, the search's and the reported ones alike.
NONNEGATIVE = ("Fc", "Fv", "Ia")
#: Default grid of a shape velocity [rad/s]: factors of 2 to 2.5 from 0.02 to 0.5 rad/s.
SHAPE_GRID = (0.02, 0.05, 0.1, 0.2, 0.5)


class Term(NamedTuple):
    """One effect on one joint, or on a motor that turns with several joints: a block of columns of
    the model.

    A coupled term acts through a transmission (a coupled wrist: one motor turns with q5 + q6): its
    columns are the effect's in the motor coordinate s = Σ_i c_i q_i (``coupling`` c, (n,)), and it
    adds c_i × its torque to joint i's row, τ = cᵀ τ_motor (DESIGN: transmissions and coupled joints).
    With c a row of the reduction matrix R (m = R q) its coefficients are the motor's own.

    Attributes:
        effect: a key of ``EFFECTS``.
        joint: active joint index (a coupled term: its first joint).
        shape: the shape velocity [rad/s] of a shaped effect (Stribeck v_s, held v_h), else None.
        coupling: (n,) the motor coordinate's weights over the joints, or None (the joint's own row).
    """

    effect: str
    joint: int
    shape: Optional[float] = None
    coupling: Optional[tuple[float, ...]] = None

    @property
    def kind(self) -> Effect:
        """Its :class:`Effect`."""
        return EFFECTS[self.effect]

    @property
    def joints(self) -> tuple[int, ...]:
        """The joints whose rows it touches."""
        return (self.joint,) if self.coupling is None else tuple(int(j) for j in np.flatnonzero(self.coupling))

    @property
    def family(self) -> tuple:
        """What a model holds at most one of: the effect on these joints (any shape or coupling ratio)."""
        return (self.effect, self.joint, self.joints)

    def rows(self, n: int) -> np.ndarray:
        """(n,) the weight of its torque on each joint's row."""
        if self.coupling is not None:
            return np.asarray(self.coupling, dtype=float)
        out = np.zeros(n)
        out[self.joint] = 1.0
        return out

    def where(self, joints: list[str]) -> str:
        """The joint, or the motor coordinate, e.g. ``panda_joint5`` or ``q5 + q6`` by name."""
        if self.coupling is None:
            return joints[self.joint]
        text = ""
        for k, j in enumerate(self.joints):
            c = self.coupling[j]
            size = "" if abs(abs(c) - 1.0) < 1e-12 else f"{abs(c):g}·"
            sign = ("−" if c < 0 else "") if k == 0 else (" − " if c < 0 else " + ")
            text += f"{sign}{size}{joints[j]}"
        return text

    def label(self, joints: list[str]) -> str:
        """e.g. ``held panda_joint7 (v_h 0.1 rad/s)``, ``motor of j5 + j6`` (its inertia, Coulomb and
        viscous friction), ``motor panda_joint4`` (a joint's own, declared)."""
        shape = f" ({self.kind.shape} {self.shape:g} rad/s)" if self.shape else ""
        where = self.where(joints) if self.coupling is None else f"motor of {self.where(joints)}"
        return (
            f"{where}{shape}"
            if self.effect == "motor" and self.coupling is not None
            else f"{self.effect} {where}{shape}"
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
        shape: the shape velocity [rad/s] of a shaped effect (Stribeck v_s, held v_h).
        rigid: (T,) the joint's rigid-body torque [Nm], needed by two-stage effects only.
        q_range: (lo, hi) [rad], the joint's q range over the fit data: a position effect's columns
            are evaluated at q clipped to it (held at their value at the nearer end, the guard
            against extrapolating to positions the fit never saw); None: no guard.

    Raises:
        KeyError: unknown effect.
        ValueError: a two-stage effect without ``rigid``, a shaped effect without its shape.
    """
    kind = EFFECTS[effect]
    if kind.two_stage and rigid is None:
        raise ValueError(f"{effect} needs the rigid-body torque")
    if kind.shape and not shape:
        raise ValueError(f"{effect} needs its shape velocity {kind.shape}")
    if kind.position and q_range is not None:
        q = np.clip(q, *q_range)
    return np.column_stack(kind.columns(Signals(q, qd, qdd, np.tanh(qd / coulomb_velocity), shape, rigid)))


def nonnegative_columns(terms: list[Term], sizes: list[int]) -> np.ndarray:
    """(Σ sizes,) which columns of the effect blocks ``terms`` (``sizes`` columns each) have a
    coefficient of ``NONNEGATIVE`` (an offset's per-run columns never do)."""
    return np.concatenate(
        [np.zeros(0, dtype=bool)]
        + [
            np.zeros(size, dtype=bool) if t.kind.per_run else np.isin(t.kind.coefficients, NONNEGATIVE)
            for t, size in zip(terms, sizes)
        ]
    )


def coefficient_names(term: Term, offset_runs: list[str]) -> list[str]:
    """Names of a term's coefficients: the effect's, an offset per run as ``tau0[run label]`` when
    the fit has several runs (``offset_runs``)."""
    names = term.kind.coefficients
    if term.kind.per_run and len(offset_runs) > 1:
        return [f"{names[0]}[{label}]" for label in offset_runs]
    return list(names)
