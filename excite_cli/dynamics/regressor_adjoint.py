"""The gradient of a weighted sum of regressor entries, Σ_t ⟨W_t, Y(x_t)⟩, in one reverse pass of RNEA (numba).

The analytic gradient of every criterion (Eqs. 45–47) is of this form: with ∂f/∂C = Σ_r a_r (C v_r)
v_rᵀ, the rows of C at instant t are Y(x_t) X, so ∂f/∂x_t = ∂/∂x_t Σ_k τ_k(x_t; φ_{t,k}), where
τ_k(x; φ) = Y_k(x) φ is the inverse dynamics of regressor row k with "virtual" inertial parameters
φ_{t,k} = X (Σ_r a_r (C v_r)_{t,k} v_r) (any values, not necessarily physical).

The function g(x) = Σ_k τ_k(x; φ_k) is a scalar, so its gradient in (q, q̇, q̈) costs a small multiple
of one RNEA by reverse-mode differentiation, whatever the number of rows, where pinocchio's RNEA
derivatives give the full n × n Jacobians of one φ per call (one call per row whose subtrees meet:
7 per instant for the G1's arms). In spatial algebra (Featherstone, *Rigid Body Dynamics
Algorithms*, 2008, ch. 5), with body j's velocity v_j, acceleration a_j (gravity as a₀ = −g) and
the axis of row k seen in body j's frame s_kj = ʲX_k S_k,

    g = Σ_j Σ_{k above or at j} ⟨s_kj, I(φ_kj) a_j + v_j ×* I(φ_kj) v_j⟩,

since τ_k = S_kᵀ Σ_{j below k} ᵏX_j* f_j. The forward pass computes v_j, a_j and s_kj down the tree;
the reverse pass takes their adjoints up it, with d(ⁱX_λ y)/dq_i = (ⁱX_λ y) × S_i for a joint whose
axis S_i is constant in its own frame (revolute or prismatic, as :func:`load_robot` ensures for the
active joints). Held joints keep their placement at the reference configuration and do not move;
the held floating base's wrench, when it is a regressor row (``robot.base_wrench_rows``), is six
rows with the unit axes of its frame. pinocchio stays the reference: tests compare with its
analytic RNEA derivatives.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from excite_cli.dynamics.kinematics import BatchKinematics
from excite_cli.dynamics.robot import Robot


class RegressorAdjoint:
    """Gradients of Σ_t Σ_k τ_k(x_t; φ_{t,k}) of ``robot`` in its active joints' positions, velocities
    and accelerations.

    Args:
        robot: the robot (active joints revolute or prismatic, as :func:`load_robot` ensures).
    """

    def __init__(self, robot: Robot):
        chain = BatchKinematics(robot)
        model = robot.model
        self.robot = robot
        self._chain = chain
        self._axes = np.zeros((robot.n_joints, 6))  # S (linear, angular) of each active joint, its own frame
        for k in range(robot.n_joints):
            self._axes[k, 3 * int(chain.revolute[k]) : 3 * int(chain.revolute[k]) + 3] = chain.axes[k]
        # each regressor row: its joint and its axis in that joint's frame (the base wrench: unit axes)
        joint_of_v = {
            model.joints[j].idx_v + i: (j, i) for j in range(1, model.njoints) for i in range(model.joints[j].nv)
        }
        self._row_joint = np.array([joint_of_v[int(v)][0] for v in robot.row_idx], dtype=np.int64)
        self._row_axis = np.zeros((robot.n_rows, 6))
        for r, v in enumerate(robot.row_idx):
            j, i = joint_of_v[int(v)]
            column = chain._column.get(j)
            if column is None:
                self._row_axis[r, i] = 1.0
            else:
                self._row_axis[r] = self._axes[column]
        # the rows above or at each joint, root first: a joint's list extends its parent's
        lists: list[list[int]] = [[]]
        for j in range(1, model.njoints):
            lists.append(lists[chain.parents[j]] + [r for r in range(robot.n_rows) if self._row_joint[r] == j])
        width = max(1, max(len(rows) for rows in lists))
        self._rows_above = np.full((model.njoints, width), -1, dtype=np.int64)
        self._inherited = np.zeros(model.njoints, dtype=np.int64)
        for j, rows in enumerate(lists):
            self._rows_above[j, : len(rows)] = rows
            self._inherited[j] = len(lists[chain.parents[j]]) if j > 0 else 0
        self._counts = np.array([len(rows) for rows in lists], dtype=np.int64)
        self._gravity = np.array(model.gravity.linear)

    def row_derivatives(
        self, phis: np.ndarray, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """∂/∂(q_t, q̇_t, q̈_t) of Σ_k τ_k(x_t; φ_{t,k}) over the regressor rows k, for each instant.

        Args:
            phis: (T, n_rows, p) standard inertial parameters φ_{t,k} in the robot's order (any values).
            Q, QD, QDD: (T, n) active joints' positions [rad], velocities [rad/s], accelerations [rad/s²].

        Returns:
            Three (T, n) arrays: the derivatives in q, q̇ and q̈ of the active joints.
        """
        T, n = Q.shape
        out = np.zeros((3, T, n))
        c = self._chain
        params = np.ascontiguousarray(phis.reshape(T, self.robot.n_rows, -1, 10))
        _reverse_pass(
            c._parents, c.fixed_R, c.fixed_p, c._columns, c.revolute, self._axes, self._row_axis,
            self._rows_above, self._counts, self._inherited, self._gravity,
            np.ascontiguousarray(Q), np.ascontiguousarray(QD), np.ascontiguousarray(QDD), params, out,
        )  # fmt: skip
        return out[0], out[1], out[2]


@njit(cache=True)
def _motion_to_child(E, p, y, out):
    """ⁱX_λ y: a motion vector (linear, angular) from the parent's frame to the child's, the child
    placed at rotation E and origin p in the parent."""
    w0, w1, w2 = y[3], y[4], y[5]
    l0 = y[0] + w1 * p[2] - w2 * p[1]
    l1 = y[1] + w2 * p[0] - w0 * p[2]
    l2 = y[2] + w0 * p[1] - w1 * p[0]
    for i in range(3):
        out[i] = E[0, i] * l0 + E[1, i] * l1 + E[2, i] * l2
        out[3 + i] = E[0, i] * w0 + E[1, i] * w1 + E[2, i] * w2


@njit(cache=True)
def _force_to_parent(E, p, f, out):
    """ⁱX_λᵀ f added to out: a force vector (linear, angular) from the child's frame to the parent's."""
    fl0 = E[0, 0] * f[0] + E[0, 1] * f[1] + E[0, 2] * f[2]
    fl1 = E[1, 0] * f[0] + E[1, 1] * f[1] + E[1, 2] * f[2]
    fl2 = E[2, 0] * f[0] + E[2, 1] * f[1] + E[2, 2] * f[2]
    out[0] += fl0
    out[1] += fl1
    out[2] += fl2
    for i in range(3):
        out[3 + i] += E[i, 0] * f[3] + E[i, 1] * f[4] + E[i, 2] * f[5]
    out[3] += p[1] * fl2 - p[2] * fl1
    out[4] += p[2] * fl0 - p[0] * fl2
    out[5] += p[0] * fl1 - p[1] * fl0


@njit(cache=True)
def _cross_motion(x, y, out):
    """x × y of two motion vectors."""
    out[0] = x[4] * y[2] - x[5] * y[1] + x[1] * y[5] - x[2] * y[4]
    out[1] = x[5] * y[0] - x[3] * y[2] + x[2] * y[3] - x[0] * y[5]
    out[2] = x[3] * y[1] - x[4] * y[0] + x[0] * y[4] - x[1] * y[3]
    out[3] = x[4] * y[5] - x[5] * y[4]
    out[4] = x[5] * y[3] - x[3] * y[5]
    out[5] = x[3] * y[4] - x[4] * y[3]


@njit(cache=True)
def _cross_force(x, f, out, sign):
    """out += sign · (x ×* f): a motion vector x acting on a force vector f."""
    out[0] += sign * (x[4] * f[2] - x[5] * f[1])
    out[1] += sign * (x[5] * f[0] - x[3] * f[2])
    out[2] += sign * (x[3] * f[1] - x[4] * f[0])
    out[3] += sign * (x[4] * f[5] - x[5] * f[4] + x[1] * f[2] - x[2] * f[1])
    out[4] += sign * (x[5] * f[3] - x[3] * f[5] + x[2] * f[0] - x[0] * f[2])
    out[5] += sign * (x[3] * f[4] - x[4] * f[3] + x[0] * f[1] - x[1] * f[0])


@njit(cache=True)
def _inertia_times(phi, y, out, sign):
    """out += sign · I(φ) y: the spatial inertia of dynamic parameters φ = (m, mc, I_xx, I_xy, I_yy,
    I_xz, I_yz, I_zz) (about the frame's origin, pinocchio's order) times a motion vector y."""
    m, c0, c1, c2 = phi[0], phi[1], phi[2], phi[3]
    v0, v1, v2, w0, w1, w2 = y[0], y[1], y[2], y[3], y[4], y[5]
    out[0] += sign * (m * v0 + w1 * c2 - w2 * c1)
    out[1] += sign * (m * v1 + w2 * c0 - w0 * c2)
    out[2] += sign * (m * v2 + w0 * c1 - w1 * c0)
    out[3] += sign * (c1 * v2 - c2 * v1 + phi[4] * w0 + phi[5] * w1 + phi[7] * w2)
    out[4] += sign * (c2 * v0 - c0 * v2 + phi[5] * w0 + phi[6] * w1 + phi[8] * w2)
    out[5] += sign * (c0 * v1 - c1 * v0 + phi[7] * w0 + phi[8] * w1 + phi[9] * w2)


@njit(cache=True)
def _dot(x, y):
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2] + x[3] * y[3] + x[4] * y[4] + x[5] * y[5]


@njit(cache=True)
def _placement(R0, p0, axis, revolute, q, E, P):
    """A joint's placement in its parent (rotation E, origin P): the fixed part (R0, p0), then its
    motion, a rotation about its axis (Rodrigues' formula) or a translation along it."""
    if not revolute:
        E[:] = R0
        for i in range(3):
            P[i] = p0[i] + (R0[i, 0] * axis[0] + R0[i, 1] * axis[1] + R0[i, 2] * axis[2]) * q
        return
    s, c = np.sin(q), 1.0 - np.cos(q)  # I + s K + c K², K = [a]×, K² = a aᵀ − I
    x, y, z = axis[3], axis[4], axis[5]
    M = np.empty((3, 3))
    M[0, 0], M[1, 1], M[2, 2] = 1.0 + c * (x * x - 1.0), 1.0 + c * (y * y - 1.0), 1.0 + c * (z * z - 1.0)
    M[0, 1], M[1, 0] = c * x * y - s * z, c * x * y + s * z
    M[0, 2], M[2, 0] = c * x * z + s * y, c * x * z - s * y
    M[1, 2], M[2, 1] = c * y * z - s * x, c * y * z + s * x
    E[:] = R0 @ M
    P[:] = p0


@njit(cache=True)
def _forward(
    t, parents, fixed_R, fixed_p, columns, revolute, axes, row_axis, rows_above, counts, inherited, Q, QD, QDD, s
):
    """Down the tree at instant t: placements s.E, s.P, velocities s.vel, accelerations s.acc (and their
    parts carried from the parent, s.moved_v, s.moved_a), each joint's own motion s.spin = S q̇, the
    rows' axes in each body's frame s.seen."""
    E, P, vel, acc, moved_v, moved_a, spin, seen = s
    tmp = np.empty(6)
    for j in range(1, parents.shape[0]):
        up, k = parents[j], columns[j]
        spin[j, :] = 0.0
        if k >= 0:
            _placement(fixed_R[j], fixed_p[j], axes[k], revolute[k], Q[t, k], E[j], P[j])
            for i in range(6):
                spin[j, i] = axes[k, i] * QD[t, k]
        else:
            E[j], P[j] = fixed_R[j], fixed_p[j]
        _motion_to_child(E[j], P[j], vel[up], moved_v[j])
        _motion_to_child(E[j], P[j], acc[up], moved_a[j])
        for i in range(6):
            vel[j, i] = moved_v[j, i] + spin[j, i]
        _cross_motion(vel[j], spin[j], tmp)
        for i in range(6):
            acc[j, i] = moved_a[j, i] + tmp[i] + (axes[k, i] * QDD[t, k] if k >= 0 else 0.0)
        for m in range(inherited[j]):
            _motion_to_child(E[j], P[j], seen[up, m], seen[j, m])
        for m in range(inherited[j], counts[j]):
            seen[j, m] = row_axis[rows_above[j, m]]


@njit(cache=True)
def _reverse(t, parents, columns, axes, rows_above, counts, inherited, params, s, out):
    """Up the tree at instant t: the adjoints of a_j, v_j and s_kj (abar, vbar, sbar), and from them
    ∂g/∂(q, q̇, q̈) into out[:, t]."""
    E, P, vel, acc, moved_v, moved_a, spin, seen = s
    J, width = parents.shape[0], rows_above.shape[1]
    vbar, abar, sbar = np.zeros((J, 6)), np.zeros((J, 6)), np.zeros((J, width, 6))
    h, tmp = np.empty(6), np.empty(6)
    for j in range(J - 1, 0, -1):
        for m in range(counts[j]):  # the terms ⟨s, I a + v ×* I v⟩ of body j
            phi, axis = params[t, rows_above[j, m], j - 1], seen[j, m]
            _inertia_times(phi, axis, abar[j], 1.0)
            h[:] = 0.0
            _inertia_times(phi, vel[j], h, 1.0)
            _cross_force(axis, h, vbar[j], -1.0)
            _cross_motion(vel[j], axis, tmp)
            _inertia_times(phi, tmp, vbar[j], -1.0)
            _inertia_times(phi, acc[j], sbar[j, m], 1.0)
            _cross_force(vel[j], h, sbar[j, m], 1.0)
        k = columns[j]
        if k >= 0:  # a = X a_λ + S q̈ + v × S q̇, v = X v_λ + S q̇, s_kj = X s_kλ
            S = axes[k]
            out[2, t, k] += _dot(S, abar[j])
            _cross_force(spin[j], abar[j], vbar[j], 1.0)
            tmp[:] = vbar[j]
            _cross_force(vel[j], abar[j], tmp, -1.0)
            out[1, t, k] += _dot(S, tmp)
            _cross_motion(moved_a[j], S, tmp)
            dq = _dot(abar[j], tmp)
            _cross_motion(moved_v[j], S, tmp)
            dq += _dot(vbar[j], tmp)
            for m in range(inherited[j]):
                _cross_motion(seen[j, m], S, tmp)
                dq += _dot(sbar[j, m], tmp)
            out[0, t, k] += dq
        up = parents[j]
        if up > 0:
            _force_to_parent(E[j], P[j], abar[j], abar[up])
            _force_to_parent(E[j], P[j], vbar[j], vbar[up])
            for m in range(inherited[j]):
                _force_to_parent(E[j], P[j], sbar[j, m], sbar[up, m])


@njit(cache=True)
def _reverse_pass(
    parents, fixed_R, fixed_p, columns, revolute, axes, row_axis, rows_above, counts, inherited, gravity,
    Q, QD, QDD, params, out,
):  # fmt: skip
    """Fill out (3, T, n) with ∂g_t/∂(q, q̇, q̈), g_t = Σ_j Σ_k ⟨s_kj, f_j(φ_{t,k,j})⟩ (module docstring)."""
    J, width = parents.shape[0], rows_above.shape[1]
    state = (
        np.zeros((J, 3, 3)), np.zeros((J, 3)), np.zeros((J, 6)), np.zeros((J, 6)),
        np.zeros((J, 6)), np.zeros((J, 6)), np.zeros((J, 6)), np.zeros((J, width, 6)),
    )  # fmt: skip
    state[3][0, :3] = -gravity  # a₀ = −g: gravity as the root's acceleration
    for t in range(Q.shape[0]):
        _forward(
            t,
            parents,
            fixed_R,
            fixed_p,
            columns,
            revolute,
            axes,
            row_axis,
            rows_above,
            counts,
            inherited,
            Q,
            QD,
            QDD,
            state,
        )
        _reverse(t, parents, columns, axes, rows_above, counts, inherited, params, state, out)
