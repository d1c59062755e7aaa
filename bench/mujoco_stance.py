"""A standing robot in MuJoCo playing a trajectory: the independent check of the zero-moment point.

MuJoCo compiles the URDF itself (its own inertias, integrator and soft contacts); the robot gets a free
joint at its root, the collision geometry of the support links (spheres, boxes, capsules: its soles) as
its only contacts, and a floor under their lowest point. The joints the problem does not move are held
at their locked values, welded (rigid, as excite's model holds them) or by a PD controller (the
stance's compliance), to which the held joints' feed-forward (:mod:`~excite_cli.design.held_joints`) or
an ankle stabilizer that regulates the centre of mass may be added; each moving joint gets the
feed-forward torque plus a PD on the tracking error
(MuJoCo's position actuators, whose damping its ``implicitfast`` integrator takes implicitly). The
centre of pressure comes from the floor's contact forces (``mj_contactForce``), the support polygon
from MuJoCo's contact points standing still (MuJoCo documentation: Computation, Contact; Programming,
Simulation).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from excite_cli.constraints.support import SupportPolygon
from excite_cli.errors import ExciteError
from excite_cli.identification.reporting.mjcf_out import import_mujoco, urdf_spec, weld_joints

#: Simulation step [s]; the played samples come at its rate.
TIMESTEP = 0.0005
#: Seconds standing still at the first sample before the motion starts.
SETTLE = 2.0
#: PD gains of the moving joints' tracking [Nm/rad, Nm·s/rad] (beside the feed-forward torque).
TRACKING_GAINS = (200.0, 10.0)
#: A robot whose root drops more than this below its standing height has fallen [m] ...
FALL_DROP = 0.05
#: ... or a sole tilted more than this from its standing orientation [deg] (a foot on its edge) ...
FALL_SOLE_TILT = 5.0
#: ... or its root more than this [deg].
FALL_ROOT_TILT = 20.0
#: Radius [m] of the spheres a mesh sole's contact points get (as the G1's foot spheres in Menagerie).
SOLE_SPHERE = 0.005
#: Geometry MuJoCo keeps as the soles' contacts (a URDF's meshes are visual or collision hulls).
CONTACT_GEOMS = ("sphere", "box", "capsule", "cylinder", "ellipsoid")


@dataclass(frozen=True)
class Stance:
    """How the joints that do not move are held at their locked values.

    Attributes:
        stiffness: PD stiffness [Nm/rad], or None: welded (rigid).
        damping: PD damping [Nm·s/rad].
        feedforward: the PD's joints also get the held joints' feed-forward torque (``export``'s).
        stabilizer: (k_p [N·m/m], k_d [N·m·s/m]) of an ankle stabilizer, or None: each sole gets the
            moment ẑ × (k_p e + k_d ė) / (number of soles) from the centre of mass's horizontal offset
            e from where it stood (Kajita et al., *Introduction to Humanoid Robotics*, 2014, ch. 4:
            ankle torque moves the centre of pressure against the CoM's error), through the two
            hinges nearest the sole.
    """

    stiffness: float | None = None
    damping: float = 0.0
    feedforward: bool = False
    stabilizer: tuple[float, float] | None = None

    def __str__(self) -> str:
        if self.stiffness is None:
            return "welded"
        added = "+feedforward" if self.feedforward else ("+stabilizer" if self.stabilizer else "")
        return f"pd{self.stiffness:g}/{self.damping:g}{added}"


@dataclass(frozen=True)
class StandingRun:
    """What MuJoCo measured while the robot played the samples.

    Attributes:
        time: (S,) [s] from the start of the motion.
        cop: (S, 2) centre of pressure [m], world x, y (NaN while no foot touches).
        com: (S, 2) centre of mass [m], world x, y.
        polygon: the support polygon of MuJoCo's contact points standing still (of the most contacts
            while settling, where the robot fell while standing still).
        tilt_deg: (S,) the largest tilt of a support link from its standing orientation [deg].
        root_tilt_deg: (S,) the root's tilt from its standing orientation [deg].
        drop: (S,) how far the root is below its standing height [m].
        tracking: (S,) the largest tracking error of a moving joint [rad].
    """

    time: np.ndarray
    cop: np.ndarray
    com: np.ndarray
    polygon: SupportPolygon
    tilt_deg: np.ndarray
    root_tilt_deg: np.ndarray
    drop: np.ndarray
    tracking: np.ndarray

    @property
    def margin(self) -> np.ndarray:
        """(S,) the centre of pressure's distance inside the support polygon [m] (−inf with no contact)."""
        inside = self.polygon.margins(np.nan_to_num(self.cop, nan=np.inf))
        return np.where(np.isnan(self.cop).any(axis=1), -np.inf, inside)

    @property
    def fell(self) -> bool:
        """Whether the root dropped more than ``FALL_DROP`` below its standing height, a sole tilted more
        than ``FALL_SOLE_TILT`` or the root more than ``FALL_ROOT_TILT``."""
        return bool(
            self.drop.max() > FALL_DROP
            or self.tilt_deg.max() > FALL_SOLE_TILT
            or self.root_tilt_deg.max() > FALL_ROOT_TILT
        )


def standing_model(
    urdf: Path,
    active: list[str],
    locked: dict[str, float],
    support_links: list[str],
    stance: Stance,
    joint_losses: tuple[float, float, float] = (0.0, 0.0, 0.0),
    soles: dict[str, tuple[np.ndarray, np.ndarray]] | None = None,
):
    """MuJoCo's model of the robot of ``urdf`` standing on the contact geometry of ``support_links``.

    Args:
        urdf: the robot's URDF.
        active: the joints that move (tracked by PD on top of the feed-forward torque).
        locked: {joint: value [rad]} of the held joints (0 for those not named).
        support_links: the links whose collision geometry touches the floor.
        stance: how the other joints are held.
        joint_losses: what every joint of the robot has that its URDF does not say: MuJoCo's joint
            ``damping`` [Nm·s/rad], ``armature`` [kg·m²] and ``frictionloss`` [Nm] (MuJoCo
            documentation, XML reference, joint).
        soles: {support link: ((k, 3) its contact points [m], (3,) the world's up)} in the link's frame at
            the standing posture, for the links whose sole is a mesh (no sphere, box or capsule): each
            point gets a sphere of ``SOLE_SPHERE`` radius whose bottom it is.

    Returns:
        The compiled ``mujoco.MjModel``: the root's free joint first, then the joints of the URDF less
        the welded ones, an actuator per remaining joint named after it.

    Raises:
        ExciteError: MuJoCo is missing or cannot read the URDF; no contact geometry on the support links.
    """
    mujoco, spec = urdf_spec(urdf)
    kinds = {getattr(mujoco.mjtGeom, f"mjGEOM_{k.upper()}") for k in CONTACT_GEOMS}
    for geom in list(spec.geoms):
        if geom.parent.name not in support_links or geom.type not in kinds:
            spec.delete(geom)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    bodies = {b.name: b for b in spec.bodies}
    for link, (points, up) in (soles or {}).items():
        if not any(g.parent.name == link for g in spec.geoms):
            for point in points:
                centre = point + SOLE_SPHERE * up
                bodies[link].add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[SOLE_SPHERE, 0, 0], pos=centre)
    if not spec.geoms:
        raise ExciteError("constraints.zmp.support_links", "MuJoCo finds no sphere, box or capsule on these links")
    # a URDF's massless links (romeo's finger frames) and zero or singular inertias (iCub's ankle, b1's base
    # frame), which MuJoCo refuses on a moving body: bounded to the least MuJoCo accepts (compiler
    # boundmass, boundinertia, balanceinertia: MuJoCo documentation, XML reference, compiler)
    spec.compiler.boundmass, spec.compiler.boundinertia, spec.compiler.balanceinertia = 1e-6, 1e-9, True
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    if stance.stiffness is None:
        weld_joints(mujoco, spec, active, locked, [])
    for joint in list(spec.joints):
        joint.damping[0], joint.armature, joint.frictionloss = joint_losses
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE  # the PD of a held joint is not a motor
        gains = TRACKING_GAINS if joint.name in active else (stance.stiffness, stance.damping)
        actuator = spec.add_actuator(name=joint.name, target=joint.name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        actuator.gainprm[0] = gains[0]
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        actuator.biasprm[:3] = [0.0, -gains[0], -gains[1]]
    spec.worldbody.first_body().add_freejoint()
    model = spec.compile()
    data = mujoco.MjData(model)
    _pose(model, data, {name: locked.get(name, 0.0) for name in _joint_names(model)})
    mujoco.mj_forward(model, data)
    lowest = min(data.geom_xpos[g, 2] - _depth(mujoco, model, data, g) for g in range(model.ngeom))
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[5.0, 5.0, 0.1], pos=[0.0, 0.0, lowest])
    return spec.compile()


def _joint_names(model) -> list[str]:
    """The names of the model's joints after the free joint."""
    return [model.joint(j).name for j in range(1, model.njnt)]


def _pose(model, data, values: dict[str, float]) -> None:
    """The root at the world origin, at rest, and the named joints at their values [rad]."""
    data.qpos[:] = 0.0
    data.qpos[3] = 1.0  # the free joint's unit quaternion
    for name, value in values.items():
        data.qpos[model.jnt_qposadr[model.joint(name).id]] = value


def _depth(mujoco, model, data, geom: int) -> float:
    """How far below its centre a contact geom reaches [m]: a sphere's radius, a box's half-extent in
    z, else its bounding sphere's radius."""
    size, rotation = model.geom_size[geom], data.geom_xmat[geom].reshape(3, 3)
    if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_SPHERE:
        return float(size[0])
    if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_BOX:
        return float(np.abs(rotation[2]) @ size)
    return float(model.geom_rbound[geom])


def play_standing(
    model,
    active: list[str],
    locked: dict[str, float],
    q: np.ndarray,
    qd: np.ndarray,
    tau: np.ndarray,
    data=None,
    held: tuple[tuple[str, ...], np.ndarray] | None = None,
    stabilizer: tuple[float, float] | None = None,
    push: np.ndarray | None = None,
) -> StandingRun:
    """Stand ``SETTLE`` seconds at the first sample, then play the samples, one per ``TIMESTEP``.

    Args:
        model: :func:`standing_model`'s.
        active: the moving joints, the columns of q, q̇, τ.
        locked: {joint: value [rad]} the held joints' set points.
        q, qd, tau: (S, n) positions [rad], velocities [rad/s] and feed-forward torques [Nm].
        data: the ``mujoco.MjData`` to play in (default: a new one); it holds the last state afterwards.
        held: the held joints' names (h,) and feed-forward torques (S, h) [Nm], added to their PD.
        stabilizer: (k_p [N·m/m], k_d [N·m·s/m]) of :attr:`Stance.stabilizer`, or None.
        push: (S, 3) a force [N] (world frame) on the root at each sample, or None.

    Returns:
        What MuJoCo measured at each sample.
    """
    mujoco = import_mujoco()
    data = mujoco.MjData(model) if data is None else data
    names = _joint_names(model)
    _pose(model, data, {name: locked.get(name, 0.0) for name in names} | dict(zip(active, q[0])))
    qpos = np.array([model.jnt_qposadr[model.joint(name).id] for name in active])
    dofs = np.array([model.jnt_dofadr[model.joint(name).id] for name in active])
    moved = np.array([model.actuator(name).id for name in active])
    data.ctrl[:] = [locked.get(model.actuator(a).name, 0.0) for a in range(model.nu)]
    damping = TRACKING_GAINS[1]
    supports = sorted({int(model.geom_bodyid[g]) for g in range(model.ngeom) if model.geom_bodyid[g] > 0})
    held_dofs = np.array([model.jnt_dofadr[model.joint(name).id] for name in held[0]]) if held else None
    ankles = _ankle_hinges(model, supports)
    com_start, com_before = None, None

    def step(k: int, force: np.ndarray | float) -> None:
        nonlocal com_before
        data.ctrl[moved] = q[k]
        data.qfrc_applied[:] = 0.0
        data.qfrc_applied[dofs] = tau[k] + damping * qd[k]  # the PD's damping acts on the error q̇_ref − q̇
        if held:
            data.qfrc_applied[held_dofs] += held[1][k]
        data.xfrc_applied[1, :3] = force
        if stabilizer and com_start is not None:
            com = data.subtree_com[1, :2].copy()
            error = np.r_[com - com_start, 0.0]
            rate = np.r_[(com - com_before) / model.opt.timestep, 0.0]
            com_before = com
            moment = np.cross([0.0, 0.0, 1.0], stabilizer[0] * error + stabilizer[1] * rate) / len(supports)
            for joint in ankles:
                data.qfrc_applied[model.jnt_dofadr[joint]] += data.xaxis[joint] @ moment
        mujoco.mj_step(model, data)

    mujoco.mj_forward(model, data)
    posed = float(data.qpos[2])
    contacts = np.zeros((0, 2))
    for _ in range(int(round(SETTLE / model.opt.timestep))):
        step(0, 0.0)
        if data.ncon > len(contacts):  # the soles' contacts while most of them touch
            contacts = np.array([data.contact[i].pos[:2] for i in range(data.ncon)])
    standing_height = float(data.qpos[2])
    com_start = com_before = data.subtree_com[1, :2].copy()
    upright = [data.xmat[b].reshape(3, 3)[:, 2].copy() for b in supports + [1]]
    if data.ncon < 3:  # fell while standing still (a stance that cannot hold its own weight): the drop from where
        standing_height = posed  # it was posed, the polygon of its contacts before
    else:
        contacts = np.array([data.contact[i].pos[:2] for i in range(data.ncon)])
    polygon = SupportPolygon.from_points(contacts, 0.0)
    count = len(q)
    cop, com = np.full((count, 2), np.nan), np.zeros((count, 2))
    tilt, drop, tracking = np.zeros((count, len(upright))), np.zeros(count), np.zeros(count)
    for k in range(count):
        step(k, 0.0 if push is None else push[k])
        cop[k], com[k] = _centre_of_pressure(mujoco, model, data), data.subtree_com[1, :2]
        tilt[k] = [
            np.degrees(np.arccos(np.clip(data.xmat[b].reshape(3, 3)[:, 2] @ z, -1.0, 1.0)))
            for b, z in zip(supports + [1], upright)
        ]
        drop[k] = standing_height - data.qpos[2]
        tracking[k] = np.abs(data.qpos[qpos] - q[k]).max()
    time = np.arange(count) * model.opt.timestep
    return StandingRun(time, cop, com, polygon, tilt[:, :-1].max(axis=1), tilt[:, -1], drop, tracking)


def _centre_of_pressure(mujoco, model, data) -> np.ndarray:
    """(2,) world x, y [m] of the floor's contact forces' centre of pressure (NaN with no contact)."""
    pressure, total, force = np.zeros(2), 0.0, np.zeros(6)
    for i in range(data.ncon):
        contact = data.contact[i]
        mujoco.mj_contactForce(model, data, i, force)
        up = abs((contact.frame.reshape(3, 3).T @ force[:3])[2])  # friction lies in the floor's plane
        pressure += up * contact.pos[:2]
        total += up
    return pressure / total if total > 0 else np.full(2, np.nan)


def _ankle_hinges(model, supports: list[int]) -> list[int]:
    """The two hinge joints nearest each support body (its ankle)."""
    mujoco = import_mujoco()
    found = []
    for body in supports:
        hinges = []
        while body > 0 and len(hinges) < 2:
            for j in range(model.body_jntadr[body], model.body_jntadr[body] + model.body_jntnum[body]):
                if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
                    hinges.append(j)
            body = int(model.body_parentid[body])
        found += hinges[:2]
    return found
