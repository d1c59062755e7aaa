"""The identification's blocks of effect columns: one effect (:data:`excite_cli.effects.EFFECTS`) on
one joint, or on a motor that turns with several joints (:class:`Term`), its columns on one joint's
samples, which of them are kept ≥ 0, and their coefficients' names."""

from __future__ import annotations

from typing import NamedTuple, Optional

import numpy as np

from excite_cli.effects import EFFECTS, NONNEGATIVE, Effect, signals


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
    return np.column_stack(kind.columns(signals(q, qd, qdd, coulomb_velocity, shape, rigid)))


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


def rotor_terms(n: int, terms: list[Term]) -> list[Term]:
    """The armature of each of the ``n`` joints that no uncoupled term of ``terms`` already holds (an
    ``armature`` or a joint's own ``motor``): the rotors the physically consistent fit keeps as bodies
    of their own (:mod:`~excite_cli.identification.choice.consistent_model`) beside the model's effects."""
    held = {t.joint for t in terms if t.coupling is None and "armature" in (t.effect, *t.kind.parts)}
    return [Term("armature", j) for j in range(n) if j not in held]
