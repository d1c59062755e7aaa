"""Effect columns beside the base regressor: Y = [Y_B | Y_E], what an identification model holds beyond
the rigid body (Coulomb and viscous friction, armature, a torque offset, coupled motors), so a
trajectory can be designed to excite them too (Swevers, Ganseman, Tükel, De Schutter, Van Brussel,
IEEE Trans. Robotics and Automation 13(5), 1997: the excitation designed for the full model, friction
included).

Every column acts in a motor coordinate s = N q, N (n,) a transmission row (a joint's own effect: N = e_j),
and reaches joint m's row times N_m (τ_m += N_m c f(ṡ, s̈), the motor torque mapped by Nᵀ):

    coulomb f = tanh(ṡ / v_c),  viscous f = ṡ,  armature f = s̈,  offset f = 1,

each the column of its record in :data:`excite_cli.effects.EFFECTS` (those a design holds, with the
derivatives of f in ṡ and s̈ that the gradient takes, :meth:`EffectColumns.chain`), the same column
identify fits. v_c is the config's ``effects.coulomb_velocity`` (default 0.01 rad/s, identify's own).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from excite_cli.config import EffectsConfig
from excite_cli.effects import DESIGNED, EFFECTS, Signals, signals
from excite_cli.errors import ExciteError, ExciteWarning

#: A typical effect's torque at the joint's limits, as a fraction of its effort limit (the scaled
#: criterion's magnitude of an effect coefficient, :meth:`EffectColumns.magnitudes`).
TYPICAL_SHARE = 0.05


@dataclass(frozen=True)
class EffectColumns:
    """The e effect columns of a design.

    Attributes:
        kinds: (e,) each column's effect (a name of :data:`~excite_cli.effects.DESIGNED`).
        transmissions: (e, n) each column's transmission row N over the active joints.
        names: (e,) coefficient names, such as ``Fc_elbow_joint`` or ``Ia_motor_wrist_2+wrist_3``.
        coulomb_velocity: v_c [rad/s] of the smooth sign.
        n_rows: regressor rows per instant; the active joints' rows are the last n.
    """

    kinds: tuple[str, ...]
    transmissions: np.ndarray
    names: tuple[str, ...]
    coulomb_velocity: float
    n_rows: int

    @property
    def count(self) -> int:
        """e, the number of columns."""
        return len(self.kinds)

    @property
    def units(self) -> tuple[str, ...]:
        """(e,) the coefficients' units."""
        return tuple(EFFECTS[k].units[0] for k in self.kinds)

    def _motion(self, QD: np.ndarray, QDD: np.ndarray) -> list[Signals]:
        """Each column's motor coordinate's ṡ, s̈ (T,) from q̇, q̈ (T, n), as :class:`Signals` (no q)."""
        sd, sdd = QD @ self.transmissions.T, QDD @ self.transmissions.T
        return [signals(None, sd[:, c], sdd[:, c], self.coulomb_velocity) for c in range(self.count)]

    def columns(self, QD: np.ndarray, QDD: np.ndarray) -> np.ndarray:
        """Y_E (T·n_rows, e) at T instants of q̇ [rad/s] and q̈ [rad/s²] (T, n), rows as the base regressor's."""
        motion = self._motion(QD, QDD)
        values = np.stack([EFFECTS[kind].columns(s)[0] for kind, s in zip(self.kinds, motion)], axis=1)  # (T, e)
        T, n = QD.shape
        out = np.zeros((T, self.n_rows, self.count))
        out[:, self.n_rows - n :, :] = values[:, None, :] * self.transmissions.T[None, :, :]
        return out.reshape(T * self.n_rows, self.count)

    def chain(self, gradient: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The derivative of a function of Y_E in q̇ and q̈ (each (T, n)) from its derivative in Y_E,
        ``gradient`` (T·n_rows, e). No column depends on q."""
        T, n = QD.shape
        g = np.einsum(
            "tmc,cm->tc", gradient.reshape(T, self.n_rows, self.count)[:, self.n_rows - n :], self.transmissions
        )
        slopes = [EFFECTS[kind].slopes(s) for kind, s in zip(self.kinds, self._motion(QD, QDD))]
        d_velocity, d_acceleration = (np.stack(d, axis=1) for d in zip(*slopes))  # (T, e) each
        return (g * d_velocity) @ self.transmissions, (g * d_acceleration) @ self.transmissions

    def magnitudes(self, effort: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray) -> np.ndarray:
        """(e,) a typical value of each coefficient: the one whose torque at the joints' limits is
        ``TYPICAL_SHARE`` of their effort limit (1 Nm where the URDF gives none).

        Args:
            effort: (n,) effort limits [Nm] (0 or inf where none); velocity, acceleration: (n,) the
                design's limits [rad/s, rad/s²].
        """
        torque = TYPICAL_SHARE * np.where(np.isfinite(effort) & (effort > 0), effort, 1.0 / TYPICAL_SHARE)
        out = np.empty(self.count)
        for c, (kind, row) in enumerate(zip(self.kinds, self.transmissions)):
            moved = row != 0
            tau = float(np.mean(torque[moved] / np.abs(row[moved])))
            speed = float(np.max(np.abs(row) * velocity))
            rate = float(np.max(np.abs(row) * acceleration))
            out[c] = tau / (1.0, speed, rate)[EFFECTS[kind].per]
        return out

    def subset(self, keep: np.ndarray) -> EffectColumns:
        """The columns where ``keep`` (e,) is true."""
        index = np.flatnonzero(keep)
        return replace(
            self,
            kinds=tuple(self.kinds[i] for i in index),
            transmissions=self.transmissions[index],
            names=tuple(self.names[i] for i in index),
        )

    def beside(self, rigid: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> EffectColumns:
        """These columns without those in the span of the rigid-body columns ``rigid`` (M, b) and of the
        columns kept before them, on the same M rows of the motion q̇, q̈ (T, n) (e.g. a joint's armature,
        which regroups with its link's inertia about the joint axis): they cannot be told apart from the
        rigid body, so they are left out with an :class:`~excite_cli.errors.ExciteWarning` naming them."""
        Y = self.columns(QD, QDD)
        kept, keep = rigid, np.zeros(self.count, dtype=bool)
        for c in range(self.count):
            residual = Y[:, c] - kept @ np.linalg.lstsq(kept, Y[:, c], rcond=None)[0]
            keep[c] = np.linalg.norm(residual) > 1e-6 * np.linalg.norm(Y[:, c])
            kept = np.hstack([kept, Y[:, c : c + 1]]) if keep[c] else kept
        if not keep.all():
            dropped = ", ".join(n for n, k in zip(self.names, keep) if not k)
            warnings.warn(
                f"effects: {dropped}: the rigid-body base parameters already hold these columns (a joint's "
                "armature that regroups with its link's inertia), left out",
                ExciteWarning,
            )
        return self.subset(keep)


def coefficient_name(kind: str, joints: Sequence[str], motor: bool = False) -> str:
    """The name of an effect coefficient (of a record of :data:`~excite_cli.effects.DESIGNED`):
    ``Fc_elbow_joint`` on a joint's own row, ``Ia_motor_wrist_2+wrist_3`` for a motor that turns with
    the ``joints`` named."""
    symbol = EFFECTS[kind].coefficients[0]
    return f"{symbol}_motor_{'+'.join(joints)}" if motor else f"{symbol}_{joints[0]}"


def effect_columns(cfg: EffectsConfig, joint_names: list[str], n_rows: int) -> EffectColumns | None:
    """The effect columns ``cfg`` asks for over the active joints ``joint_names`` (n), each joint's in
    :data:`~excite_cli.effects.DESIGNED`'s order, joints in their order, then each motor's columns
    (its effect's parts: armature, Coulomb and viscous friction); None when it asks for none.

    Raises:
        ExciteError: a joint that is not active (``effects.joints``, ``effects.motors``), or a motor whose
            transmission row does not give one ratio per joint.
    """
    n, kinds, rows, names = len(joint_names), [], [], []
    for key in cfg.joints:
        if key != "*" and key not in joint_names:
            raise ExciteError("effects.joints", f"'{key}' is not an active joint (or '*' for all)")
    for j, joint in enumerate(joint_names):
        wanted = set(cfg.joints.get("*", [])) | set(cfg.joints.get(joint, []))
        for kind in (k for k in DESIGNED if k in wanted):
            kinds.append(kind)
            rows.append(np.eye(n)[j])
            names.append(coefficient_name(kind, [joint]))
    for i, motor in enumerate(cfg.motors):
        field = f"effects.motors[{i}]"
        unknown = [name for name in motor.joints if name not in joint_names]
        if unknown:
            raise ExciteError(f"{field}.joints", f"'{unknown[0]}' is not an active joint")
        if len(motor.transmission) != len(motor.joints):
            raise ExciteError(
                f"{field}.transmission", f"{len(motor.transmission)} ratios for {len(motor.joints)} joints"
            )
        row = np.zeros(n)
        for name, ratio in zip(motor.joints, motor.transmission):
            row[joint_names.index(name)] += ratio
        for kind in EFFECTS["motor"].parts:
            kinds.append(kind)
            rows.append(row)
            names.append(coefficient_name(kind, motor.joints, motor=True))
    if not kinds:
        return None
    return EffectColumns(tuple(kinds), np.array(rows), tuple(names), cfg.coulomb_velocity, n_rows)
