"""One effect the rigid-body model lacks, everything about it in one record: its columns, what it
refines, how identification searches it, and, where a trajectory can be designed for it, the
derivatives of its column that the design's gradient takes (Swevers, Ganseman, Tükel, De Schutter,
Van Brussel, IEEE Trans. Robotics and Automation 13(5), 1997: the excitation designed for the full
model, friction included)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, NamedTuple, Optional

import numpy as np


class Signals(NamedTuple):
    """One joint's (or one motor coordinate's) samples an effect's columns are made of, in time order
    (T,) each: q [rad] (None in a design, whose columns do not depend on it), q̇ [rad/s], q̈ [rad/s²],
    the smooth sign tanh(q̇/v_c) and its v_c [rad/s], the shape velocity of a shaped effect [rad/s]
    and the joint's rigid-body torque [Nm] of a two-stage effect (None where not needed)."""

    q: Optional[np.ndarray]
    qd: np.ndarray
    qdd: np.ndarray
    sign: np.ndarray
    coulomb_velocity: float
    shape: Optional[float] = None
    rigid: Optional[np.ndarray] = None


def signals(
    q: Optional[np.ndarray],
    qd: np.ndarray,
    qdd: np.ndarray,
    coulomb_velocity: float,
    shape: Optional[float] = None,
    rigid: Optional[np.ndarray] = None,
) -> Signals:
    """The :class:`Signals` of samples q, q̇, q̈ (T,) [rad, rad/s, rad/s²], their smooth sign taken with
    ``coulomb_velocity`` v_c [rad/s]."""
    return Signals(q, qd, qdd, np.tanh(qd / coulomb_velocity), coulomb_velocity, shape, rigid)


#: The derivatives (∂f/∂q̇, ∂f/∂q̈) (T,) each of an effect's one column f(q̇, q̈).
Slopes = Callable[[Signals], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Effect:
    """One candidate effect.

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
        coupled: proposed only on motors that turn with several joints (identification's ``Term``
            ``coupling``), never as a joint's own candidate.
        parts: the effects whose columns it is made of, in order (a motor: its rotor inertia, Coulomb
            and viscous friction), or none.
        slopes: a design holds it as a column beside the base regressor (``effects.joints`` of an
            optimize config): (∂f/∂q̇, ∂f/∂q̈) of its one column f, which depends on q̇ and q̈ only;
            None: identification only (a column of q, of a shape, of the history or of a first fit).
        per: what a typical coefficient is a torque per, at the joints' limits: 0 nothing (a torque),
            1 their velocity, 2 their acceleration (the design's scaled criterion).
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
    parts: tuple[str, ...] = ()
    slopes: Optional[Slopes] = None
    per: int = 0

    @property
    def designed(self) -> bool:
        """A design holds it as a column (it has :attr:`slopes`)."""
        return self.slopes is not None

    def unit(self, coefficient: str) -> str:
        """The unit of one of its coefficients."""
        return self.units[self.coefficients.index(coefficient)]


def combined(name: str, parts: tuple[Effect, ...], **kinds: bool) -> Effect:
    """An effect made of ``parts``' columns in order (their coefficients, units and columns), with the
    flags ``kinds`` (e.g. ``motor=True``)."""
    return Effect(
        name,
        tuple(c for p in parts for c in p.coefficients),
        tuple(u for p in parts for u in p.units),
        lambda s: [column for p in parts for column in p.columns(s)],
        parts=tuple(p.name for p in parts),
        **kinds,
    )


def held_sign(qd: np.ndarray, held_velocity: float) -> np.ndarray:
    """(T,) 1(abs(q̇) < v_h) · sign of the last sample (in time order) with abs(q̇) ≥ v_h (0 before any)."""
    moving = np.abs(qd) >= held_velocity
    last = np.maximum.accumulate(np.where(moving, np.arange(qd.size), -1))
    return np.where(~moving & (last >= 0), np.sign(qd[np.maximum(last, 0)]), 0.0)
