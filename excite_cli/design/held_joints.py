"""What the held joints of a standing robot must give while its active joints move: their
feed-forward torques, exported beside the active joints'.

A floating-base problem holds the base fixed and the joints it does not move (legs, waist) at their
locked values (:mod:`~excite_cli.dynamics.robot`); a lab holds them by their own joint controllers on
soft contacts, which sway under the arms' motion unless each held joint is also given the torque that
keeps the base and itself at rest. With the soles flat on the ground, contact points c (the soles'
lowest collision points, :func:`~excite_cli.constraints.support.sole_points`) and a force f_c at each
(world frame), the equations of motion of the full model (free flyer and every joint) with the base
and held joints at rest split as (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, ch. 9)

    RNEA(q, q̇, q̈)_base = Σ_c J_c,baseᵀ f_c    (6 rows: the ground wrench of :mod:`~excite_cli.constraints.zmp`)
    τ_held = RNEA(q, q̇, q̈)_held − Σ_c J_c,heldᵀ f_c

with q̇, q̈ zero but for the active joints'. The six rows leave 3C − 6 of the forces free; they are
split as task-space inverse dynamics splits them (Del Prete, Mansard et al., *Implementing torque
control with high-ratio gear boxes and without joint-torque sensors*, IJHR 2016; the tsid library):
the least-norm forces f = A⁺ w, kept where every one lies in its friction cone ‖f_xy‖ ≤ μ f_z, else
the quadratic program min ‖f‖² s.t. A f = w, f_c in its cone (Clarabel, second-order cones). A force
in its cone pushes (f_z ≥ 0), so each sole's centre of pressure, the f_z-weighted mean of its contact
points, stays inside the hull of that sole's points. The feet do not move, so J_c is constant.
"""

from __future__ import annotations

from dataclasses import dataclass

import clarabel
import numpy as np
import pinocchio as pin
from scipy import sparse

from excite_cli.config import ConstraintsConfig
from excite_cli.config.constraints import ZmpConfig
from excite_cli.constraints.support import sole_points
from excite_cli.constraints.zmp import CONTACT_HEIGHT, has_floating_base
from excite_cli.dynamics.robot import Robot
from excite_cli.dynamics.robot_files import robot_source
from excite_cli.errors import ExciteError

#: A contact force counts as inside its cone within this relative tolerance (of μ f_z, rounding).
CONE_TOLERANCE = 1e-9


@dataclass(frozen=True)
class HeldTorques:
    """The held joints' feed-forward at the samples of a played motion.

    Attributes:
        joint_names: (h,) the held joints, in the model's order (for a joint of several degrees of
            freedom, one name per degree: ``<joint>_<k>``).
        positions: (h,) the values [rad] they are held at.
        tau: (S, h) the torques [Nm] that keep the base and the held joints at rest.
        forces: (S, C, 3) the contact forces [N] (world frame) at the soles' contact points.
        points: (C, 3) those contact points [m] (world frame, base at the identity).
        effort: (h,) the URDF's effort limits [Nm] (0 or inf: none given).
        slipping: how many samples no split of the ground wrench keeps every force in its friction
            cone (the robot would tip or slip): their forces are the least-norm split.
        friction: μ of the cones the forces were split in.
    """

    joint_names: tuple[str, ...]
    positions: np.ndarray
    tau: np.ndarray
    forces: np.ndarray
    points: np.ndarray
    effort: np.ndarray
    slipping: int
    friction: float = 0.0

    def peak(self) -> tuple[int, float]:
        """The held joint (its index) whose |τ| is the largest share of its effort limit (of |τ| where no
        joint has a limit), and that share (the torque [Nm] where no joint has a limit)."""
        use = np.abs(self.tau).max(axis=0)
        limited = np.isfinite(self.effort) & (self.effort > 0)
        share = np.where(limited, use / np.where(limited, self.effort, 1.0), 0.0)
        k = int(np.argmax(share)) if limited.any() else int(np.argmax(use))
        return k, float(share[k] if limited.any() else use[k])


class HeldJoints:
    """The feed-forward of the joints ``robot`` holds, for the robot standing on ``soles``.

    Args:
        full: the robot's pinocchio model with its free flyer and every joint (none locked).
        robot: the problem's robot (its active joints and home posture).
        links: the support links (soles).
        soles: each support link's contact points (k_i, 3) [m], world frame, at least 3 in all not on
            one line.
        friction: μ of the soles on the ground.
        locked: {joint: value [rad]} of the held joints (0 for those not named).
        field: the config field that names ``links``, for the messages.

    Raises:
        ExciteError: (``field``) contact points that cannot carry a wrench (on one line).
    """

    def __init__(
        self,
        full: pin.Model,
        robot: Robot,
        links: list[str],
        soles: list[np.ndarray],
        friction: float,
        locked: dict[str, float],
        field: str,
    ):
        self.full, self.data, self.friction = full, full.createData(), float(friction)
        active = [full.getJointId(name) for name in robot.joint_names]
        self.q_idx = np.array([full.idx_qs[j] for j in active])
        self.v_idx = np.array([full.idx_vs[j] for j in active])
        held = [j for j in range(2, full.njoints) if j not in active]
        self.held_v = np.concatenate([np.arange(full.idx_vs[j], full.idx_vs[j] + full.nvs[j]) for j in held])
        self.names = tuple(
            full.names[j] if full.nvs[j] == 1 else f"{full.names[j]}_{k}" for j in held for k in range(full.nvs[j])
        )
        self.q_reference = pin.neutral(full)
        for name, value in locked.items():
            self.q_reference[full.idx_qs[full.getJointId(name)]] = value
        self.q_reference[self.q_idx] = robot.home
        self.positions = np.concatenate([self.q_reference[full.idx_qs[j] : full.idx_qs[j] + full.nqs[j]] for j in held])
        self.points = np.vstack(soles)
        jacobian = self._contact_jacobian(links, soles)  # (3C, nv)
        self.A, self.G = jacobian[:, :6].T, jacobian[:, self.held_v].T  # base rows, held rows
        if np.linalg.matrix_rank(self.A) < 6:
            raise ExciteError(field, "the soles' contact points lie on one line")
        self.A_pinv = np.linalg.pinv(self.A)
        self.effort = full.effortLimit[self.held_v].copy()

    def _contact_jacobian(self, links: list[str], soles: list[np.ndarray]) -> np.ndarray:
        """(3C, nv) the contact points' linear-velocity Jacobians (world frame) at the reference posture:
        v_c = v_o + ω × (c − o) of the support link's joint o."""
        full, data = self.full, self.data
        pin.computeJointJacobians(full, data, self.q_reference)
        rows = []
        for link, points in zip(links, soles):
            joint = full.frames[full.getFrameId(link)].parentJoint
            J = pin.getJointJacobian(full, data, joint, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            origin = data.oMi[joint].translation
            rows += [J[:3] - pin.skew(c - origin) @ J[3:] for c in points]
        return np.vstack(rows)

    def torques(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> HeldTorques:
        """The held joints' feed-forward while the active joints play q, q̇, q̈ (S, n) [rad, rad/s, rad/s²]."""
        count = len(q)
        tau, forces, slipping = np.empty((count, len(self.names))), np.empty((count, len(self.points), 3)), 0
        qf, v, a = self.q_reference.copy(), np.zeros(self.full.nv), np.zeros(self.full.nv)
        for k in range(count):
            qf[self.q_idx], v[self.v_idx], a[self.v_idx] = q[k], qd[k], qdd[k]
            rnea = pin.rnea(self.full, self.data, qf, v, a)
            f, inside = self.contact_forces(rnea[:6])
            slipping += not inside
            forces[k] = f.reshape(-1, 3)
            tau[k] = rnea[self.held_v] - self.G @ f
        return HeldTorques(self.names, self.positions, tau, forces, self.points, self.effort, slipping, self.friction)

    def contact_forces(self, wrench: np.ndarray) -> tuple[np.ndarray, bool]:
        """The contact forces f (3C,) [N] (world frame, point by point) that give the ground wrench
        ``wrench`` (6,) (force [N], moment about the world origin [N·m]): the least-norm ones where
        they lie in their cones, else the cone-constrained quadratic program's; and whether they lie
        in their cones (False: no split does, the least-norm one is returned)."""
        f = self.A_pinv @ wrench
        if self.in_cones(f):
            return f, True
        found = self._cone_split(wrench)
        return (f, False) if found is None else (found, True)

    def in_cones(self, f: np.ndarray) -> bool:
        """Whether every contact force of f (3C,) [N] is inside its friction cone ‖f_xy‖ ≤ μ f_z."""
        f = f.reshape(-1, 3)
        return bool(np.all(np.hypot(f[:, 0], f[:, 1]) <= self.friction * f[:, 2] * (1 + CONE_TOLERANCE)))

    def _cone_split(self, wrench: np.ndarray) -> np.ndarray | None:
        """min ‖f‖² s.t. A f = ``wrench`` (6,), each force in its cone (Clarabel); None when none exists."""
        C = len(self.points)
        cone = sparse.kron(sparse.eye(C), sparse.csc_matrix([[0.0, 0.0, -self.friction], [-1, 0, 0], [0, -1, 0]]))
        A = sparse.vstack([sparse.csc_matrix(self.A), cone]).tocsc()
        b = np.concatenate([wrench, np.zeros(3 * C)])
        cones = [clarabel.ZeroConeT(6)] + [clarabel.SecondOrderConeT(3)] * C
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        solution = clarabel.DefaultSolver(
            sparse.eye(3 * C, format="csc"), np.zeros(3 * C), A, b, cones, settings
        ).solve()
        if solution.status != clarabel.SolverStatus.Solved:
            return None
        return np.asarray(solution.x)


def held_joints(robot_cfg, folder, constraints: ConstraintsConfig, robot: Robot) -> HeldJoints | None:
    """The :class:`HeldJoints` of a standing problem: a floating base on the soles of
    ``constraints.zmp.support_links`` (else ``constraints.com.support_links``), μ of ``constraints.zmp``;
    None for a fixed base or a problem that names no soles.

    Raises:
        ExciteError: as :meth:`~excite_cli.dynamics.source.RobotSource.model`,
            :func:`~excite_cli.constraints.support.sole_points` and :class:`HeldJoints`.
    """
    zmp, com = constraints.zmp, constraints.com
    links = zmp.support_links if zmp else (com.support_links if com else None)
    if not (has_floating_base(robot) and links):
        return None
    field = "constraints.zmp.support_links" if zmp else "constraints.com.support_links"
    friction = zmp.friction if zmp else ZmpConfig.model_fields["friction"].default
    full = robot_source(robot_cfg, folder).model(True)
    soles = sole_points(robot, links, CONTACT_HEIGHT, field)
    return HeldJoints(full, robot, links, soles, friction, dict(robot_cfg.locked_joints), field)
