"""The robot: a pinocchio model reduced to the joints that move, and its torque regressor (Eq. 1).

A floating-base robot (humanoid) keeps its free-flyer joint, held fixed at the identity pose: its
base velocity and acceleration are zero, and the 6 base-wrench rows of the regressor can be used
when the robot has foot force sensors. Every joint that is not active is locked at its configured
value (default 0) and its body is merged into its parent (``pinocchio.buildReducedModel``), as the
paper does with HRP-4's legs and waist (Section IV-B).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from excite_cli.config import RobotConfig
from excite_cli.dynamics.active_joints import check_joints, unknown_joint
from excite_cli.dynamics.robot_files import open_source, robot_source
from excite_cli.dynamics.source import apply_joint_ranges
from excite_cli.dynamics.urdf_meshes import package_folders
from excite_cli.errors import ExciteError

#: Order of pinocchio's 10 dynamic parameters of one body (``Inertia.toDynamicParameters``).
PARAMETER_SYMBOLS = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")


@dataclass
class Robot:
    """Reduced pinocchio model with the active joints' indices and limits.

    Attributes:
        model: reduced pinocchio model (locked joints removed).
        joint_names: the n active joints, in config order.
        q_idx, v_idx: (n,) indices of the active joints in the model's q and v.
        row_idx: (n_rows,) indices in v of the regressor rows: the base wrench (6) if requested, then
            the active joints.
        q_reference: (model.nq,) configuration with the base at identity and locked joints set.
        lower, upper: (n,) URDF position limits [rad].
        velocity_limit: (n,) URDF velocity limits [rad/s] (0 or inf where the URDF has none).
        body_names: (model.njoints - 1,) the link carried by each joint, for parameter names.
        home: (n,) posture [rad] the random starts oscillate about (config ``robot.home_posture``,
            default 0, clipped into the URDF position limits).
        collision_model: the URDF's collision geometry attached to the reduced model, if loaded.
        links: (parent, child) names of consecutive joint frames (moving, locked or fixed) of the
            full URDF tree, for drawing the robot (the reduced model's frames keep no parent for
            locked joints).
        angle_rounding: largest rounding [rad] of a right (or 15°) angle in the URDF
            (:func:`~excite_cli.dynamics.urdf_rounding.angle_rounding`; 0 for an MJCF).
    """

    model: pin.Model
    joint_names: list[str]
    q_idx: np.ndarray
    v_idx: np.ndarray
    row_idx: np.ndarray
    q_reference: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    velocity_limit: np.ndarray
    body_names: list[str]
    home: np.ndarray
    collision_model: pin.GeometryModel | None = None
    links: list[tuple[str, str]] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    angle_rounding: float = 0.0
    data: pin.Data = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.data = self.model.createData()

    @property
    def n_joints(self) -> int:
        """Number n of active joints."""
        return len(self.joint_names)

    @property
    def n_rows(self) -> int:
        """Regressor rows per time instant."""
        return len(self.row_idx)

    @property
    def n_parameters(self) -> int:
        """Number p of standard inertial parameters (10 per body of the reduced model)."""
        return 10 * (self.model.njoints - 1)

    @property
    def parameter_names(self) -> list[str]:
        """(p,) names such as ``Izz_left_elbow_link``."""
        return [f"{s}_{body}" for body in self.body_names for s in PARAMETER_SYMBOLS]

    def urdf_parameters(self) -> np.ndarray:
        """(p,) a-priori standard parameters φ from the URDF [kg, kg·m, kg·m²]."""
        return np.concatenate([self.model.inertias[j].toDynamicParameters() for j in range(1, self.model.njoints)])

    def state(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Full model (q, v, a) from the active joints' (n,) values; base and locked joints at rest."""
        qf = self.q_reference.copy()
        vf = np.zeros(self.model.nv)
        af = np.zeros(self.model.nv)
        qf[self.q_idx] = q
        vf[self.v_idx] = qd
        af[self.v_idx] = qdd
        return qf, vf, af

    def states(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`state` of T samples at once: the full model's (q, v, a) (T, nq), (T, nv), (T, nv) from
        the active joints' (T, n) values."""
        full_q = np.tile(self.q_reference, (len(q), 1))
        full_v, full_a = np.zeros((2, len(q), self.model.nv))
        full_q[:, self.q_idx], full_v[:, self.v_idx], full_a[:, self.v_idx] = q, qd, qdd
        return full_q, full_v, full_a

    def regressor(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, data: pin.Data | None = None) -> np.ndarray:
        """Torque regressor Y(q, q̇, q̈) of Eq. 1, rows ``row_idx``: (n_rows, p).

        Args:
            q, qd, qdd: (n,) active joints' position [rad], velocity [rad/s], acceleration [rad/s²].
            data: the caller's pinocchio Data (each consumer keeps its own; default: the robot's).
        """
        Y = pin.computeJointTorqueRegressor(self.model, data or self.data, *self.state(q, qd, qdd))
        return Y.reshape(self.model.nv, -1)[self.row_idx]  # a one-joint model's comes back flat

    def regressor_stack(
        self, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray, data: pin.Data | None = None
    ) -> np.ndarray:
        """Regressors at T instants stacked as in Eq. 3: (T·n_rows, p) from (T, n) arrays."""
        return np.vstack([self.regressor(Q[t], QD[t], QDD[t], data) for t in range(Q.shape[0])])

    def torques(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, data: pin.Data | None = None) -> np.ndarray:
        """Inverse dynamics τ (RNEA) of the URDF model, rows ``row_idx``: (n_rows,) [Nm, N]."""
        return pin.rnea(self.model, data or self.data, *self.state(q, qd, qdd))[self.row_idx].copy()

    def com(self, q: np.ndarray, data: pin.Data | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Centre of total mass [m] (3,) in the world frame, of the URDF inertias, and its Jacobian
        (3, n) in the active joints (base held fixed) [m/rad]."""
        data = data or self.data
        qf = self.q_reference.copy()
        qf[self.q_idx] = q
        J = pin.jacobianCenterOfMass(self.model, data, qf, False).reshape(3, self.model.nv)
        return data.com[0].copy(), J[:, self.v_idx]

    def random_states(self, count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(count, n) random positions within the limits, and standard-normal velocities and accelerations."""
        lo = np.where(np.isfinite(self.lower), self.lower, -np.pi)
        hi = np.where(np.isfinite(self.upper), self.upper, np.pi)
        Q = rng.uniform(lo, hi, size=(count, self.n_joints))
        return Q, rng.standard_normal(Q.shape), rng.standard_normal(Q.shape)


def joint_frame_links(model: pin.Model) -> list[tuple[str, str]]:
    """(parent, child) names of each joint frame (moving or fixed) and its nearest joint-frame ancestor."""
    kinds = (pin.FrameType.JOINT, pin.FrameType.FIXED_JOINT)
    pairs = []
    for index, frame in enumerate(model.frames):
        if index == 0 or frame.type not in kinds:
            continue
        parent = frame.parentFrame
        while 0 < parent < index and model.frames[parent].type not in kinds:
            parent = model.frames[parent].parentFrame
        pairs.append((model.frames[parent].name, frame.name))
    return pairs


def _body_name(model: pin.Model, joint_id: int) -> str:
    for frame in model.frames:
        if frame.parentJoint == joint_id and frame.type == pin.FrameType.BODY:
            return frame.name
    return model.names[joint_id]


def load_robot(
    cfg: RobotConfig,
    folder: Path | None = None,
    collision: bool = False,
    urdf: Path | None = None,
    joint_rows_only: bool = False,
    physical: bool = True,
) -> Robot:
    """Build the :class:`Robot` of a ``robot`` section: load the URDF or MJCF, give the joints
    ``robot.joint_ranges``, lock the non-active joints.

    Args:
        cfg: the validated ``robot`` section.
        folder: the config file's folder, which a relative ``robot.urdf`` is in.
        collision: also load the URDF's collision geometry (meshes), reduced with the model.
        urdf: load this URDF file instead of ``robot.urdf`` (e.g. an identified one), with the
            section's joints.
        joint_rows_only: the regressor rows are the active joints' torques, whatever
            ``robot.base_wrench_rows`` says (identification measures joint torques).
        physical: refuse a moved link whose URDF inertia no body can have; False (identification,
            which takes the URDF's inertias as a reference only): keep it in ``Robot.warnings``.

    Raises:
        ExciteError: missing URDF, unknown joint name, a joint that is not 1-DoF, a locked value
            outside the joint's limits, a body or active joint that cannot be
            (:meth:`~excite_cli.dynamics.source.RobotSource.check`), a joint range that cannot be
            (:func:`~excite_cli.dynamics.source.apply_joint_ranges`).
    """
    source = robot_source(cfg, folder) if urdf is None else open_source(urdf, package_folders(urdf, [str(urdf.parent)]))
    active, locked = list(cfg.active_joints), list(cfg.locked_joints)
    problems = source.check(active, locked, physical)  # before urdfdom prints what it cannot parse
    full = source.model(cfg.floating_base)
    apply_joint_ranges(full, cfg.joint_ranges, source.path.name)

    movable = check_joints(cfg, full)
    q_full = pin.neutral(full)
    for name, value in cfg.locked_joints.items():
        q_full[full.idx_qs[full.getJointId(name)]] = value
    lock_ids = [full.getJointId(n) for n in movable if n not in cfg.active_joints]
    geometry = None
    if collision:
        geometry = source.geometry(full)
        try:
            model, geometry = pin.buildReducedModel(full, geometry, lock_ids, q_full)
        except ValueError as exc:  # a joint and a link of one name (so100's "gripper"): pinocchio cannot reduce
            if lock_ids:
                problem = f"pinocchio cannot hold joints of {source.path.name}: {exc}"
                raise ExciteError("robot.locked_joints", problem) from None
            model = full  # nothing to hold
    else:
        model = pin.buildReducedModel(full, lock_ids, q_full)

    ids = [model.getJointId(n) for n in cfg.active_joints]
    q_idx = np.array([model.idx_qs[j] for j in ids])
    v_idx = np.array([model.idx_vs[j] for j in ids])
    base_rows = np.arange(6) if (cfg.floating_base and cfg.base_wrench_rows and not joint_rows_only) else np.arange(0)
    if cfg.base_wrench_rows and not cfg.floating_base:
        raise ExciteError("robot.base_wrench_rows", "needs robot.floating_base: true")
    lower, upper = model.lowerPositionLimit[q_idx].copy(), model.upperPositionLimit[q_idx].copy()
    unknown = [name for name in cfg.home_posture if name not in cfg.active_joints]
    if unknown:
        raise unknown_joint("robot.home_posture", unknown[0], list(cfg.active_joints))
    home = np.array([cfg.home_posture.get(name, 0.0) for name in cfg.active_joints])
    return Robot(
        model=model,
        joint_names=list(cfg.active_joints),
        q_idx=q_idx,
        v_idx=v_idx,
        row_idx=np.concatenate([base_rows, v_idx]).astype(int),
        q_reference=pin.neutral(model),
        lower=lower,
        upper=upper,
        velocity_limit=model.velocityLimit[v_idx].copy(),
        body_names=[_body_name(model, j) for j in range(1, model.njoints)],
        home=np.clip(home, lower, upper),
        collision_model=geometry,
        links=joint_frame_links(full),
        warnings=[f"{p} in {source.path.name}: kept as the identification's reference only" for p in problems],
        angle_rounding=source.angle_rounding(),
    )
