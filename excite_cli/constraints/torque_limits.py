"""Joint torque limits |τ_i(t)| ≤ τ_max,i on the constraint grid, τ = RNEA(q, q̇, q̈) of the URDF
model (the feed-forward torque ``export`` writes), aggregated per joint and side like the joint
limits (``lse.py``): 2n inequalities on s_t = ±τ_i(t)/τ_max,i − 1.

The Jacobian in α follows from pinocchio's RNEA derivatives (Carpentier & Mansard 2018), the same
ones the criterion's gradient uses: with q_j(t) = B(t) α_j (Eq. 50),

    ∂τ_i(t)/∂α_j = ∂τ_i/∂q_j B(t) + ∂τ_i/∂q̇_j Ḃ(t) + M_ij B̈(t).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.special import logsumexp, softmax

from excite_cli.config import PerJoint
from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.constraints.joint_limits import per_joint
from excite_cli.constraints.lse import ACCEPT_MARGIN, GRID_MARGIN, SHARPNESS, smooth_max
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.trajectory.fourier import FourierBasis


class TorqueLimits(Constraint):
    """|τ| ≤ τ_max on the constraint grid, 2n aggregated inequalities.

    Args:
        robot: the robot (its URDF inertias give τ).
        basis: Fourier basis on the constraint grid.
        limit: (n,) τ_max [Nm] of the active joints, > 0.
    """

    name = "torque_limits"
    field = "limits.torque"
    grid_margin = ACCEPT_MARGIN
    eased_by_slowing = True
    track_units = {"torque_use": "fraction of the limit"}

    def __init__(self, robot: Robot, basis: FourierBasis, limit: np.ndarray):
        self.robot, self.basis, self.limit = robot, basis, np.asarray(limit, dtype=float)
        self.data = robot.model.createData()
        self._orders = (basis.q, basis.qd, basis.qdd)

    def torques(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """(T, n) RNEA torques [Nm] of the active joints at the samples q, q̇, q̈ (T, n)."""
        r = self.robot
        return np.array([pin.rnea(r.model, self.data, *r.state(*x))[r.v_idx] for x in zip(q, qd, qdd)])

    def _derivatives(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """τ (T, n) [Nm] and its derivatives (3, T, n, n) in q, q̇, q̈ of the active joints."""
        r, d = self.robot, self.data
        nv = r.model.nv
        tau, full = np.empty((q.shape[0], nv)), np.empty((3, q.shape[0], nv, nv))
        for t, x in enumerate(zip(q, qd, qdd)):
            pin.computeRNEADerivatives(r.model, d, *r.state(*x))
            tau[t], full[0, t], full[1, t], full[2, t] = d.tau, d.dtau_dq, d.dtau_dv, d.M
        upper = np.triu(full[2])  # pinocchio fills the upper triangle of M only
        full[2] = upper + np.triu(upper, 1).transpose(0, 2, 1)
        active = np.asarray(r.v_idx)
        return tau[:, active], full[:, :, active[:, None], active[None, :]]

    def _aggregated(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per side and joint, |τ|/τ_max − 1 aggregated over the grid (2, n), and the weights (2, T, n)."""
        z = tau / self.limit
        return smooth_max(np.stack([z - 1.0, -z - 1.0]), axis=1)

    def values(self, alpha: np.ndarray) -> np.ndarray:
        """The 2n values of :meth:`evaluate` from RNEA alone, without the derivatives."""
        return self._aggregated(self.torques(*(B @ alpha.T for B in self._orders)))[0].ravel()

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """2n aggregated values (side × joint) and their Jacobian (2n, α.size)."""
        n, m = alpha.shape
        tau, derivatives = self._derivatives(*(B @ alpha.T for B in self._orders))
        g, w = self._aggregated(tau)  # (2, n), (2, T, n)
        weights = w * np.array([1.0, -1.0])[:, None, None] / self.limit  # ∂g/∂τ (2, T, n)
        J = sum(np.einsum("kti,tij,tc->kijc", weights, D, B) for D, B in zip(derivatives, self._orders))
        return g.ravel(), J.reshape(2 * n, n * m)

    def check_samples(self, time: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> FineCheck:
        """Largest |τ| − τ_max [Nm] and its normalized value, and the joint and time where it is."""
        use = np.abs(self.torques(q, qd, qdd)) / self.limit  # (T, n)
        t, j = np.unravel_index(np.argmax(use), use.shape)
        details = {
            "max_violation_torque_Nm": float(np.max(np.abs(use * self.limit) - self.limit)),
            "max_torque_use": float(use.max()),
        }
        joint = self.robot.joint_names[j]
        where = f"torque of joint '{joint}' at {use[t, j]:.3f} of its limit (t = {time[t]:.2f} s)"
        return FineCheck(max_violation=float(use.max() - 1.0), details=details, where=where)

    def track(self, alpha: np.ndarray, basis: FourierBasis) -> dict[str, np.ndarray]:
        """``torque_use``: (T, n) |τ|/τ_max on ``basis``'s instants."""
        return {"torque_use": np.abs(self.torques(*basis.evaluate(alpha))) / self.limit}


class TorqueUse(TorqueLimits):
    """Minimum torque use (FloBaRoID's ``minTorqueUtilization``): each joint i with a fraction f_i > 0
    reaches |τ_i(t)| ≥ f_i τ_max,i at some instant of the constraint grid, so that its torque rises
    above the sensor noise. One inequality per such joint on a smooth maximum that never exceeds the
    true one: m_i = (1/β) log Σ_t,± exp(±β τ_i(t)/τ_max,i) − log(2T)/β ≤ max_t |τ_i(t)|/τ_max,i, and
    g_i = f_i + δ − m_i ≤ 0 (``lse.py``'s β and δ).

    A motion must exist to meet it: standing still at the home posture and the random starts need
    not (:attr:`needs_motion`); the solver moves into it.

    Args:
        robot, basis, limit: as :class:`TorqueLimits`.
        fraction: (n,) f of each active joint, 0 where none is asked.
    """

    name = "min_torque_use"
    field = "limits.min_torque_use"
    needs_motion = True
    eased_by_slowing = False  # a lower bound on the torque's peak, which a transition need not reach

    def __init__(self, robot: Robot, basis: FourierBasis, limit: np.ndarray, fraction: np.ndarray):
        super().__init__(robot, basis, limit)
        self.fraction = np.asarray(fraction, dtype=float)
        self.joints = np.flatnonzero(self.fraction > 0)

    def _soft(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """β ± τ_i/τ_max,i of the asked joints (2, T, k), and their smooth maxima m_i (k,)."""
        z = tau[:, self.joints] / self.limit[self.joints]
        both = SHARPNESS * np.stack([z, -z])
        return both, (logsumexp(both, axis=(0, 1)) - np.log(2 * z.shape[0])) / SHARPNESS

    def values(self, alpha: np.ndarray) -> np.ndarray:
        """The k values of :meth:`evaluate` from RNEA alone, without the derivatives."""
        soft = self._soft(self.torques(*(B @ alpha.T for B in self._orders)))[1]
        return self.fraction[self.joints] + GRID_MARGIN - soft

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One value per joint with a fraction (k,) and the Jacobian (k, α.size)."""
        n, m = alpha.shape
        tau, derivatives = self._derivatives(*(B @ alpha.T for B in self._orders))
        j, limit = self.joints, self.limit[self.joints]
        both, soft = self._soft(tau)  # (2, T, k), (k,)
        w = softmax(both, axis=(0, 1))
        weights = -(w[0] - w[1]) / limit  # ∂g/∂τ (T, k)
        J = sum(np.einsum("ti,tij,tc->ijc", weights, D[:, j], B) for D, B in zip(derivatives, self._orders))
        return self.fraction[j] + GRID_MARGIN - soft, J.reshape(j.size, n * m)

    def check_samples(self, time: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> FineCheck:
        """The joint that falls shortest of its fraction: f_i − max_t |τ_i|/τ_max,i (≤ 0 when met)."""
        reached = (np.abs(self.torques(q, qd, qdd)) / self.limit).max(axis=0)[self.joints]
        asked = self.fraction[self.joints]
        k = int(np.argmax(asked - reached))
        joint, shortfall = self.robot.joint_names[self.joints[k]], float(asked[k] - reached[k])
        where = f"joint {joint} reaches {reached[k]:.3f} of its torque limit at most (asked: {asked[k]:g})"
        return FineCheck(max_violation=shortfall, details={"min_torque_use_shortfall": shortfall}, where=where)


def torque_use_fraction(value: float | dict[str, float], robot: Robot) -> np.ndarray:
    """(n,) fraction of ``limits.min_torque_use`` per active joint: every joint's, or the named ones' (0 elsewhere).

    Raises:
        ExciteError: an unknown joint.
    """
    if not isinstance(value, dict):
        return np.full(robot.n_joints, float(value))
    fraction = np.zeros(robot.n_joints)
    for name, f in value.items():
        if name not in robot.joint_names:
            raise ExciteError("limits.min_torque_use", f"'{name}' is not an active joint")
        fraction[robot.joint_names.index(name)] = f
    return fraction


def torque_limit(value: PerJoint | str, robot: Robot) -> np.ndarray:
    """(n,) τ_max [Nm] of ``limits.torque``: ``urdf`` (the URDF's ``<limit effort>``), a scale factor
    of those, or {joint: Nm} (the others from the URDF).

    Raises:
        ExciteError: an unknown joint, a joint left without a positive finite limit, or an active joint
            that moves no mass (a URDF without ``<inertial>``: its torque is 0 whatever the motion).
    """
    data = robot.model.createData()
    pin.computeSubtreeMasses(robot.model, data)
    idle = [n for n in robot.joint_names if not data.mass[robot.model.getJointId(n)] > 0.0]
    if idle:
        raise ExciteError(
            "limits.torque",
            f"{', '.join(idle)} move(s) no mass in the robot's file: the torque is 0 whatever the motion, so a "
            "torque limit would check nothing",
            None,
            "the robot's inertias (<inertial> on its links), or no limits.torque",
        )
    urdf = robot.model.effortLimit[robot.v_idx].astype(float)
    if isinstance(value, dict):
        return per_joint("limits.torque", value, urdf, robot)
    return per_joint("limits.torque", None, urdf * (1.0 if value == "urdf" else float(value)), robot)
