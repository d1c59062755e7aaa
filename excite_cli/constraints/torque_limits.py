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

from excite_cli.config import PerJoint
from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.constraints.joint_limits import per_joint
from excite_cli.constraints.lse import ACCEPT_MARGIN, smooth_max
from excite_cli.dynamics.robot import Robot
from excite_cli.trajectory.fourier import FourierBasis


class TorqueLimits(Constraint):
    """|τ| ≤ τ_max on the constraint grid, 2n aggregated inequalities.

    Args:
        robot: the robot (its URDF inertias give τ).
        basis: Fourier basis on the constraint grid.
        limit: (n,) τ_max [Nm] of the active joints, > 0.
    """

    name = "torque_limits"
    grid_margin = ACCEPT_MARGIN
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

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """2n aggregated values (side × joint) and their Jacobian (2n, α.size)."""
        n, m = alpha.shape
        tau, derivatives = self._derivatives(*(B @ alpha.T for B in self._orders))
        z = tau / self.limit
        g, w = smooth_max(np.stack([z - 1.0, -z - 1.0]), axis=1)  # (2, n), (2, T, n)
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
        where = f"torque of joint {j + 1} at {use[t, j]:.3f} of its limit (t = {time[t]:.2f} s)"
        return FineCheck(max_violation=float(use.max() - 1.0), details=details, where=where)

    def track(self, alpha: np.ndarray, basis: FourierBasis) -> dict[str, np.ndarray]:
        """``torque_use``: (T, n) |τ|/τ_max on ``basis``'s instants."""
        return {"torque_use": np.abs(self.torques(*basis.evaluate(alpha))) / self.limit}


def torque_limit(value: PerJoint | str, robot: Robot) -> np.ndarray:
    """(n,) τ_max [Nm] of ``limits.torque``: ``urdf`` (the URDF's ``<limit effort>``), a scale factor
    of those, or {joint: Nm} (the others from the URDF).

    Raises:
        ExciteError: an unknown joint, or a joint left without a positive finite limit.
    """
    urdf = robot.model.effortLimit[robot.v_idx].astype(float)
    if isinstance(value, dict):
        return per_joint("limits.torque", value, urdf, robot)
    return per_joint("limits.torque", None, urdf * (1.0 if value == "urdf" else float(value)), robot)
