"""Weighted RNEA derivatives with "virtual" inertial parameters: Σ_r Σ_t w_{r,t}ᵀ ∂τ(x_t; φ_r)/∂x_t.

The analytic gradient of every criterion (Eqs. 45–47) is of this form: τ(x; φ) = Y(x) φ is inverse
dynamics, linear in φ, so the derivative of a weighted sum of regressor rows times φ_r is pinocchio's
analytic RNEA derivatives with inertias φ_r. Two things make it cheap:

- The passes run on the smallest model that gives the same torques: joints that are neither active
  nor regressor rows (the held floating base when its wrench is not used) are locked. They do not
  move, so the torques of the active joints are those of the locked model.
- φ_r need not be physical, but pinocchio needs a non-zero mass on every body. The shift φ_s gives
  body j a point mass M_j at its joint's origin and, for a revolute joint, −M_j at the same point
  of the parent body: that point lies on the joint's axis and does not move relative to the parent,
  so φ_s changes no torque derivative for any motion (it is in the regressor's null space) and
  φ_s + φ_r needs no separate shift pass. M_j = m_s × (bodies in j's subtree), so every body keeps a
  net mass m_s. A moving prismatic joint breaks this; then one extra pass with φ_s alone, weighted
  by −Σ_r w_r, removes the shift.

A criterion that needs many eigenvectors (D- or A-optimality: all b) has per-instant weights of
full rank. Then the passes are better taken per regressor row: Σ_k ∂τ_k(x_t; φ_{t,k})/∂x_t with a
virtual parameter per instant and row (:meth:`VirtualDynamics.row_derivatives`). τ_k depends only on
the bodies that joint k carries (its subtree), so rows whose subtrees do not meet (a humanoid's left
and right arms) share one pass: the passes per instant are as many as the deepest chain has rows,
7 for the G1's arms instead of b = 90.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from excite_cli.dynamics.robot import Robot


class VirtualDynamics:
    """RNEA derivatives of ``robot`` with arbitrary inertial parameters, weighted and summed.

    Args:
        robot: the robot (reduced model, active joints, regressor rows).
    """

    def __init__(self, robot: Robot):
        self.robot = robot
        held = [
            j for j in range(1, robot.model.njoints) if robot.model.joints[j].idx_v not in set(robot.v_idx.tolist())
        ]
        rows_held = robot.n_rows > robot.n_joints  # the base wrench is a regressor row
        self.model = (
            robot.model if (rows_held or not held) else pin.buildReducedModel(robot.model, held, robot.q_reference)
        )
        model = self.model
        ids = [model.getJointId(name) for name in robot.joint_names]
        self.q_idx = np.array([model.idx_qs[j] for j in ids])
        self.v_idx = np.array([model.idx_vs[j] for j in ids])
        self.row_idx = robot.row_idx if model is robot.model else self.v_idx
        self.q_reference = pin.neutral(model) if model is not robot.model else robot.q_reference
        # parameter block (in the robot's order) of each body of this model
        self.blocks = [robot.model.getJointId(model.names[j]) - 1 for j in range(1, model.njoints)]
        revolute = [model.joints[j].shortname().startswith("JointModelR") for j in range(model.njoints)]
        self.shift_free = all(
            revolute[j] for j in range(1, model.njoints) if model.joints[j].idx_v in set(self.v_idx.tolist())
        )
        self._unit_shift = self._shift_per_mass(revolute) @ self._subtree_sizes()
        self._models: list[pin.Model] = []
        self._datas: list[pin.Data] = []
        self.slots = self._row_slots()
        self._row_model = pin.Model(model)
        self._row_data = self._row_model.createData()

    def weighted_derivatives(
        self, phis: np.ndarray, weights: np.ndarray, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Σ_r w_{r,t}ᵀ ∂τ(x_t; φ_r)/∂(q_t, q̇_t, q̈_t) over the regressor rows, for each instant.

        Args:
            phis: (p, R) standard inertial parameters φ_r in the robot's parameter order (any values).
            weights: (R, T, n_rows) row weights w_{r,t}.
            Q, QD, QDD: (T, n) active joints' positions [rad], velocities [rad/s], accelerations [rad/s²].

        Returns:
            Three (T, n) arrays: the derivatives in q, q̇ and q̈ of the active joints.
        """
        R, T = phis.shape[1], Q.shape[0]
        models, datas = self._virtual_models(phis)
        nv = self.model.nv
        padded = np.zeros((len(models), T, nv))
        padded[:R, :, self.row_idx] = weights
        if len(models) > R:
            padded[-1] = -padded[:R].sum(axis=0)
        q = np.tile(self.q_reference, (T, 1))
        v, a = np.zeros((T, nv)), np.zeros((T, nv))
        q[:, self.q_idx], v[:, self.v_idx], a[:, self.v_idx] = Q, QD, QDD
        grads = np.zeros((3, T, nv))
        derivatives = np.empty((3, T, nv, nv))
        for model, data, w in zip(models, datas, padded):
            for t in range(T):
                derivatives[:, t] = pin.computeRNEADerivatives(model, data, q[t], v[t], a[t])
            grads += np.einsum("tv,ktvw->ktw", w, derivatives)
        return grads[0][:, self.v_idx], grads[1][:, self.v_idx], grads[2][:, self.v_idx]

    def row_derivatives(
        self, phis: np.ndarray, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Σ_k ∂τ_k(x_t; φ_{t,k})/∂(q_t, q̇_t, q̈_t) over the regressor rows k, for each instant: one
        virtual parameter vector per instant and row, rows whose subtrees do not meet in one pass.

        Args:
            phis: (T, n_rows, p) standard inertial parameters φ_{t,k} in the robot's order (any values).
            Q, QD, QDD: (T, n) active joints' positions [rad], velocities [rad/s], accelerations [rad/s²].

        Returns:
            Three (T, n) arrays: the derivatives in q, q̇ and q̈ of the active joints.
        """
        model, data, nv = self._row_model, self._row_data, self.model.nv
        T = Q.shape[0]
        q = np.tile(self.q_reference, (T, 1))
        v, a = np.zeros((T, nv)), np.zeros((T, nv))
        q[:, self.q_idx], v[:, self.v_idx], a[:, self.v_idx] = Q, QD, QDD
        blocks = phis.reshape(T, phis.shape[1], -1, 10)[:, :, self.blocks]  # (T, rows, bodies, 10)
        shift = (1.0 + 2.0 * np.abs(blocks[..., 0]).max()) * self._unit_shift.reshape(-1, 10)
        grads = np.zeros((3, T, nv))
        derivatives = np.empty((T, 3, nv, nv))
        inertias, inertia, rnea = model.inertias, pin.Inertia.FromDynamicParameters, pin.computeRNEADerivatives
        resting = [inertia(dynamic) for dynamic in shift]  # each body with φ_s alone
        for rows, bodies, weights in self.slots:
            for joint, held in enumerate(resting, start=1):  # the bodies outside the slot's subtrees
                inertias[joint] = held
            params, joints = shift[bodies] + blocks[:, rows, bodies], (bodies + 1).tolist()  # (T, slot bodies, 10)
            for t in range(T):
                for joint, dynamic in zip(joints, params[t]):
                    inertias[joint] = inertia(dynamic)
                derivatives[t] = rnea(model, data, q[t], v[t], a[t])
            grads += np.einsum("v,tkvw->ktw", weights, derivatives)
        if not self.shift_free:  # the shift's own derivatives, once per instant and row
            for joint, held in enumerate(resting, start=1):
                inertias[joint] = held
            for t in range(T):
                derivatives[t] = rnea(model, data, q[t], v[t], a[t])
            grads -= np.einsum("v,tkvw->ktw", sum(weights for _, _, weights in self.slots), derivatives)
        return grads[0][:, self.v_idx], grads[1][:, self.v_idx], grads[2][:, self.v_idx]

    def _row_slots(self) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Regressor rows grouped so that no two rows of a group share a body of their subtrees: per
        group, the rows (r,), each body's row among them ((r',) rows and bodies, indexing a (rows,
        bodies) array), and the group's row weights (nv,)."""
        model = self.model
        subtree = np.zeros((model.nv, model.njoints - 1), dtype=bool)  # bodies each velocity index carries
        for j in range(1, model.njoints):
            k = j
            while k > 0:
                joint = model.joints[k]
                subtree[joint.idx_v : joint.idx_v + joint.nv, j - 1] = True
                k = model.parents[k]
        groups: list[list[int]] = []
        for r, index in enumerate(self.row_idx):
            free = next((g for g in groups if not (subtree[[self.row_idx[x] for x in g]] & subtree[index]).any()), None)
            if free is None:
                groups.append([r])
            else:
                free.append(r)
        slots = []
        for g in groups:
            rows, bodies = np.nonzero(subtree[[self.row_idx[x] for x in g]])
            weights = np.zeros(model.nv)
            weights[[self.row_idx[x] for x in g]] = 1.0
            slots.append((np.array(g)[rows], bodies, weights))
        return slots

    def _virtual_models(self, phis: np.ndarray) -> tuple[list[pin.Model], list[pin.Data]]:
        """Model copies with inertias φ_s + φ_r, r < R, and one with φ_s alone unless ``shift_free``."""
        passes = phis.shape[1] + (0 if self.shift_free else 1)
        if len(self._models) != passes:
            self._models = [pin.Model(self.model) for _ in range(passes)]
            self._datas = [m.createData() for m in self._models]
        blocks = phis.reshape(-1, 10, phis.shape[1])
        shift = (1.0 + 2.0 * np.abs(blocks[:, 0, :]).max()) * self._unit_shift
        for j, block in enumerate(self.blocks, start=1):
            own = shift[10 * (j - 1) : 10 * j]
            for r, model in enumerate(self._models):
                extra = blocks[block, :, r] if r < phis.shape[1] else 0.0
                model.inertias[j] = pin.Inertia.FromDynamicParameters(own + extra)
        return self._models, self._datas

    def _subtree_sizes(self) -> np.ndarray:
        """(njoints − 1,) bodies in the subtree of each joint, itself included."""
        parents = self.model.parents
        sizes = np.ones(len(parents))
        for j in range(len(parents) - 1, 0, -1):
            sizes[parents[j]] += sizes[j]
        return sizes[1:]

    def _shift_per_mass(self, revolute: list[bool]) -> np.ndarray:
        """(10 (njoints − 1), njoints − 1): the dynamic parameters of φ_s per unit of each M_j."""
        model = self.model
        A = np.zeros((10 * (model.njoints - 1), model.njoints - 1))
        for j in range(1, model.njoints):
            A[10 * (j - 1), j - 1] = 1.0
            parent = model.parents[j]
            if parent > 0 and revolute[j]:
                point = pin.Inertia(1.0, model.jointPlacements[j].translation, np.zeros((3, 3)))
                A[10 * (parent - 1) : 10 * parent, j - 1] = -point.toDynamicParameters()
        return A
