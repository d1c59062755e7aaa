"""Forward kinematics of the reduced model at many configurations at once, in a compiled loop (numba).

pinocchio computes one configuration per call; the self-collision constraint needs every joint's
placement at every instant of the constraint grid (hundreds) in each optimizer evaluation, where the
Python loop over instants costs more than the kinematics (numba: 0.2 ms for the G1's 401 instants,
where numpy's batched products over the chain took 1.2 ms). The chain is the model's: each joint's
placement in its parent (``model.jointPlacements``) followed by its motion, a rotation about (or
translation along) the joint's axis for the active 1-DoF joints; every other joint (the held
floating base) keeps its motion at the reference configuration. pinocchio stays the reference
(tests compare both to 1e-12).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from excite_cli.dynamics.robot import Robot


class BatchKinematics:
    """Joint placements of ``robot``'s reduced model at T configurations of the active joints.

    Args:
        robot: the robot (active joints revolute or prismatic, as :func:`load_robot` ensures).

    Attributes:
        ancestors: (njoints, n) bool, whether active joint k moves joint j (k is j or above it).
        axes: (n, 3) each active joint's axis in its own frame; revolute: (n,) bool.
    """

    def __init__(self, robot: Robot):
        model = robot.model
        data = model.createData()
        pin.computeJointJacobians(model, data, robot.q_reference)
        self.robot = robot
        self.parents = list(model.parents)
        self._column = {
            j: robot.v_idx.tolist().index(model.joints[j].idx_v)
            for j in range(1, model.njoints)
            if model.joints[j].idx_v in robot.v_idx
        }
        self.joint_of = [0] * robot.n_joints
        self.axes = np.zeros((robot.n_joints, 3))
        self.revolute = np.zeros(robot.n_joints, dtype=bool)
        # fixed part of each joint's placement in its parent: jointPlacement for active joints, the
        # whole liMi at the reference configuration for held joints
        self.fixed_R = np.zeros((model.njoints, 3, 3))
        self.fixed_p = np.zeros((model.njoints, 3))
        for j in range(1, model.njoints):
            if j in self._column:
                k = self._column[j]
                S = pin.getJointJacobian(model, data, j, pin.LOCAL).reshape(6, model.nv)[:, model.joints[j].idx_v]
                self.joint_of[k] = j
                self.revolute[k] = np.linalg.norm(S[3:]) > 0.0
                axis = S[3:] if self.revolute[k] else S[:3]
                self.axes[k] = axis / np.linalg.norm(axis)
                placement = model.jointPlacements[j]
            else:
                placement = data.liMi[j]
            self.fixed_R[j], self.fixed_p[j] = placement.rotation, placement.translation
        self._parents = np.array(self.parents, dtype=np.int64)
        self._columns = np.array([self._column.get(j, -1) for j in range(model.njoints)], dtype=np.int64)
        self.ancestors = np.zeros((model.njoints, robot.n_joints), dtype=bool)
        for j in range(1, model.njoints):
            self.ancestors[j] = self.ancestors[self.parents[j]]
            if j in self._column:
                self.ancestors[j, self._column[j]] = True

    def placements(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World rotations (T, njoints, 3, 3) and origins (T, njoints, 3) [m] of every joint frame
        (``data.oMi``) at the active joints' configurations Q (T, n) [rad or m]."""
        T, J = Q.shape[0], len(self.parents)
        R, p = np.empty((T, J, 3, 3)), np.empty((T, J, 3))
        _chain(self._parents, self.fixed_R, self.fixed_p, self._columns, self.revolute, self.axes, Q, R, p)
        return R, p

    def joint_axes(self, R: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each active joint's world axis a_k and moment a_k × o_k (o_k its origin) [m] at T instants,
        (T, 3, n) each, from the joint placements (:meth:`placements`)."""
        axes = np.einsum("tkij,kj->tik", R[:, self.joint_of], self.axes)
        return axes, np.cross(axes, p[:, self.joint_of].transpose(0, 2, 1), axis=1)

    def distance_rates(self, R: np.ndarray, p: np.ndarray, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """Rates (T, K, n) at which each active joint alone moves K world points along directions n.

        Args:
            R, p: joint placements at T instants (:meth:`placements`).
            points: (3, T, K) world positions x [m]; normals: (3, T, K) directions n (coordinates
                first, as :func:`~excite_cli.collision.segments.segment_closest_points` gives them).

        Entry k is nᵀ(a_k × (x − o_k)) = a_k·(x × n) − (a_k × o_k)·n for a revolute active joint k
        (a_k its world axis, o_k its origin), nᵀa_k for a prismatic one: the velocity Jacobian of x,
        projected on n, as if x were fixed to a body below every joint. For a body, keep the columns
        of its :attr:`ancestors`. For the distance of two closest points x₁, x₂ along n ∥ x₂ − x₁,
        either point gives the same rates (x₂ × n = x₁ × n), so ∂d/∂q_k is the rate times
        ancestors[body₂, k] − ancestors[body₁, k].
        """
        axes, moments = self.joint_axes(R, p)
        turning = np.concatenate([_cross(points, normals), -normals]).transpose(1, 2, 0) @ np.concatenate(
            [axes, moments], axis=1
        )
        if self.revolute.all():
            return turning
        return np.where(self.revolute, turning, normals.transpose(1, 2, 0) @ axes)


@njit(cache=True)
def _chain(parents, fixed_R, fixed_p, columns, revolute, axes, Q, R, p):
    """Fill R (T, J, 3, 3) and p (T, J, 3) down the chain: each joint's fixed placement in its parent,
    then its motion (a rotation about its axis by Rodrigues' formula, or a translation along it)."""
    M = np.empty((3, 3))
    for t in range(Q.shape[0]):
        R[t, 0] = 0.0
        p[t, 0] = 0.0
        for i in range(3):
            R[t, 0, i, i] = 1.0
        for j in range(1, parents.shape[0]):
            up, k = parents[j], columns[j]
            for i in range(3):
                p[t, j, i] = p[t, up, i]
                for m in range(3):
                    p[t, j, i] += R[t, up, i, m] * fixed_p[j, m]
                    R[t, j, i, m] = 0.0
                    for n in range(3):
                        R[t, j, i, m] += R[t, up, i, n] * fixed_R[j, n, m]
            if k < 0:
                continue
            a = axes[k]
            if not revolute[k]:
                for i in range(3):
                    p[t, j, i] += (R[t, j, i, 0] * a[0] + R[t, j, i, 1] * a[1] + R[t, j, i, 2] * a[2]) * Q[t, k]
                continue
            s, c = np.sin(Q[t, k]), 1.0 - np.cos(Q[t, k])  # I + s K + c K², K = [a]×, K² = a aᵀ − I
            for i in range(3):
                M[i, i] = 1.0 + c * (a[i] * a[i] - 1.0)
            M[0, 1], M[1, 0] = c * a[0] * a[1] - s * a[2], c * a[0] * a[1] + s * a[2]
            M[0, 2], M[2, 0] = c * a[0] * a[2] + s * a[1], c * a[0] * a[2] - s * a[1]
            M[1, 2], M[2, 1] = c * a[1] * a[2] - s * a[0], c * a[1] * a[2] + s * a[0]
            for i in range(3):
                r0, r1, r2 = R[t, j, i, 0], R[t, j, i, 1], R[t, j, i, 2]
                for m in range(3):
                    R[t, j, i, m] = r0 * M[0, m] + r1 * M[1, m] + r2 * M[2, m]


def _cross(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """x × y of (3, ...) arrays, coordinates first (contiguous coordinate planes)."""
    return np.stack([x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]])
