"""The robot as MuJoCo compiles it for a rehearsal: its own inertias, integrator and soft contacts, which
nobody here wrote (MuJoCo documentation: Computation; XML reference).

From the URDF (or the lab's MJCF, its own actuators, tendons and sensors removed): each joint the
controller drives gets a PD actuator (MuJoCo's position actuator with damping, which its
``implicitfast`` integrator takes implicitly), the joints the problem locks and nobody drives welded at
their values. A standing robot gets a free joint at its root, its soles' contact geometry as its only
contacts (a mesh sole a 5 mm sphere at each of excite's contact points) and a floor under them; a
fixed-base arm keeps its collision geometry and gets the config's environment shapes, every contact
reported.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from excite_cli.config.constraints import ConstraintsConfig
from excite_cli.config.problem import RobotConfig
from excite_cli.config.rehearsal import RehearsalConfig
from excite_cli.dynamics.mjcf_compiled import is_mjcf
from excite_cli.errors import ExciteError
from excite_cli.identification.reporting.mjcf_out import clear_controls, resolve_meshes, urdf_spec, weld_joints

#: MuJoCo's step [s].
TIMESTEP = 0.0005
#: Radius [m] of the spheres a mesh sole's contact points get (as the G1's foot spheres in Menagerie).
SOLE_SPHERE = 0.005
#: Geometry MuJoCo keeps as the soles' contacts (a URDF's meshes are visual or collision hulls).
CONTACT_GEOMS = ("sphere", "box", "capsule", "cylinder", "ellipsoid")
#: A free joint's qpos size (position, unit quaternion).
FREE_QPOS = 7


@dataclass
class RehearsalRobot:
    """A compiled MuJoCo robot and what the controller drives.

    Attributes:
        model: the compiled ``mujoco.MjModel``; an actuator per driven joint, named after it.
        active: the joints that play the export (feed-forward + PD).
        held: {joint: value [rad]} a standing robot's joints its PD holds.
        gains: {joint: (K [N·m/rad], D [N·m·s/rad])} of every driven joint.
        standing: whether the root is free and stands on ``support_links``.
        support_links: the soles' links (standing).
        notes: what was left out or changed, in words.
    """

    model: object
    active: list[str]
    held: dict[str, float]
    gains: dict[str, tuple[float, float]]
    standing: bool
    support_links: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def require_mujoco() -> None:
    """Nothing where MuJoCo is installed.

    Raises:
        ExciteError: (``rehearse``) MuJoCo is not installed, with the one line that installs it.
    """
    try:
        import mujoco  # noqa: F401
    except ImportError:
        raise ExciteError(
            "rehearse", "plays the motion in MuJoCo, which is not installed", expected="pip install 'excite[mujoco]'"
        ) from None


def rehearsal_robot(
    robot: RobotConfig,
    constraints: ConstraintsConfig,
    urdf: Path,
    package_dirs: list[str],
    controller: RehearsalConfig,
    soles: dict[str, tuple[np.ndarray, np.ndarray]] | None = None,
    welded: bool = False,
    joint_names: dict[str, str] | None = None,
    fusestatic: bool = True,
) -> RehearsalRobot:
    """MuJoCo's robot of a problem (module docstring), from ``urdf`` (a URDF or the lab's MJCF).

    Args:
        robot: the problem's robot (its active and locked joints, floating base, home).
        constraints: its constraints (the soles, the environment, the self-collision pairs it excludes).
        urdf: the robot's file MuJoCo compiles.
        package_dirs: where a URDF's ``package://`` meshes are looked for.
        controller: the ``rehearsal`` section: the PDs of the active and the held joints, the joints'
            damping, armature and dry friction (None: the file's).
        soles: {support link: ((k, 3) its contact points [m], (3,) the world's up)} in the link's frame
            at the standing posture, for the links whose sole is a mesh.
        joint_names: {the problem's joint: the file's name for it} where they differ (a lab's MJCF).
        welded: a standing robot's held joints welded at their values (rigid, as excite's model holds
            them) instead of held by their PD.
        fusestatic: MuJoCo's ``compiler.fusestatic`` where the file sets it (a URDF): off where a link
            rests on a fixed base at home, that pair then left out (kept on, the UR3's shoulder rubbed
            its base: its pan tracked within 22° RMS instead of 0.01°).

    Returns:
        The :class:`RehearsalRobot`.

    Raises:
        ExciteError: MuJoCo is missing, cannot read the file or refuses the model; a joint of the problem
            the file does not have; no contact geometry on the soles.
    """
    mujoco, spec = urdf_spec(urdf)
    spec.compiler.fusestatic = spec.compiler.fusestatic and fusestatic  # an MJCF's default is off
    notes: list[str] = []
    if is_mjcf(urdf):
        package_dirs = [*package_dirs, str(urdf.parent / spec.meshdir)]
        clear_controls(spec, notes)
    _rename(spec, joint_names or {}, urdf)
    names = {j.name for j in spec.joints}
    missing = [j for j in robot.active_joints if j not in names]
    if missing:
        raise ExciteError(
            "mjcf",
            f"{urdf.name} has no joint {', '.join(missing)}",
            expected="the result's joints, or a map of their names",
        )
    zmp = constraints.zmp
    standing = robot.floating_base and zmp is not None
    links = list(zmp.support_links) if standing else []
    if standing:
        _soles_only(mujoco, spec, links, soles or {})
    else:
        for joint in [j for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_FREE]:
            notes.append(f"free joint {joint.name or '(unnamed)'} bolted to the world: the problem's base is fixed")
            spec.delete(joint)  # a fixed-base problem: the root bolted, as the optimizer modelled it
        resolve_meshes(spec, urdf, package_dirs, notes)
        _environment(mujoco, spec, constraints)
    spec.compiler.boundmass, spec.compiler.boundinertia, spec.compiler.balanceinertia = 1e-6, 1e-9, True
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    locked = dict(robot.locked_joints)
    driven = [j.name for j in spec.joints if j.type != mujoco.mjtJoint.mjJNT_FREE]
    held = {j: locked.get(j, 0.0) for j in driven if j not in robot.active_joints} if standing and not welded else {}
    weld_joints(mujoco, spec, list(robot.active_joints) + list(held), locked, notes)
    gains = {j: controller.active_gains.of(j) for j in robot.active_joints}
    gains |= {j: controller.held_gains.of(j) for j in held}
    losses = controller.joint_losses
    for joint in [j for j in spec.joints if j.type != mujoco.mjtJoint.mjJNT_FREE]:
        if losses is not None:
            joint.damping[0], joint.armature, joint.frictionloss = losses.damping, losses.armature, losses.frictionloss
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE  # the lab's torque limits are reported, not clipped
        stiffness, damping = gains[joint.name]
        actuator = spec.add_actuator(name=joint.name, target=joint.name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        actuator.gainprm[0] = stiffness
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        actuator.biasprm[:3] = [0.0, -stiffness, -damping]
    if standing and not any(j.type == mujoco.mjtJoint.mjJNT_FREE for j in spec.joints):
        spec.worldbody.first_body().add_freejoint()
    model = _compile(spec, urdf)
    if standing:
        spec.worldbody.add_geom(
            name="floor",
            type=mujoco.mjtGeom.mjGEOM_PLANE,
            size=[5.0, 5.0, 0.1],
            pos=[0.0, 0.0, _lowest(mujoco, model, locked)],
        )
        model = _compile(spec, urdf)
    else:
        excluded = constraints.self_collision.exclude_pairs if constraints.self_collision else []
        model, on_base = _excluded(mujoco, spec, model, locked | dict(robot.home_posture), excluded, urdf, notes)
        if on_base and spec.compiler.fusestatic:  # a link on the base MuJoCo fused into the world: again
            args = (robot, constraints, urdf, package_dirs, controller, soles, welded, joint_names)
            return rehearsal_robot(*args, fusestatic=False)  # with the base a body, so that pair is left out
    return RehearsalRobot(model, list(robot.active_joints), held, gains, standing, links, notes)


def _excluded(mujoco, spec, model, posture: dict[str, float], pairs: list, urdf: Path, notes: list[str]):
    """The model with the body pairs the config excludes from self-collision (``pairs``: capsules, and
    MuJoCo's convex hulls of the meshes, that overlap where the links do not) and those whose collision
    geometry overlaps at ``posture`` (the home) excluded from contact, as a robot's collision model leaves
    them out; each pair noted. Also whether a body touches the world's geometry at ``posture`` (a pair
    with the world is not left out: the world holds the floor and the environment)."""
    bodies = {b.name for b in spec.bodies}
    given = {tuple(sorted(p)) for p in pairs if set(p) <= bodies}
    data = mujoco.MjData(model)
    pose(model, data, {j: v for j, v in posture.items() if j in joint_names(model)})
    mujoco.mj_forward(model, data)
    touching, on_world = set(), False
    for i in range(data.ncon):
        pair = sorted(model.body(int(model.geom_bodyid[g])).name for g in data.contact[i].geom)
        if data.contact[i].dist > 0:
            continue
        if "world" in pair:
            on_world = True
        elif pair[0]:
            touching.add(tuple(pair))
    for a, b in sorted(given | touching):
        exclude = spec.add_exclude()
        exclude.bodyname1, exclude.bodyname2 = a, b
    for why, found in (("excluded by constraints.self_collision", given), ("overlapping at home", touching - given)):
        if found:
            notes.append(f"left out of contact, {why}: " + ", ".join(f"{a}-{b}" for a, b in sorted(found)))
    return (_compile(spec, urdf) if given | touching else model), on_world


def _rename(spec, joint_names: dict[str, str], urdf: Path) -> None:
    """The file's joints given the problem's names (``joint_names``: {problem's: file's}).

    Raises:
        ExciteError: (``joint_names``) a name the file does not have.
    """
    joints = {j.name: j for j in spec.joints}
    missing = [theirs for theirs in joint_names.values() if theirs not in joints]
    if missing:
        raise ExciteError("joint_names", f"{urdf.name} has no joint {', '.join(missing)}", expected="its joints' names")
    for ours, theirs in joint_names.items():
        joints[theirs].name = ours


def _compile(spec, urdf: Path):
    try:
        return spec.compile()
    except ValueError as exc:
        raise ExciteError("mjcf", f"MuJoCo cannot compile {urdf.name}: {' '.join(str(exc).split())[:300]}") from None


def _soles_only(mujoco, spec, links: list[str], soles: dict[str, tuple[np.ndarray, np.ndarray]]) -> None:
    """Every geom but the soles' contact primitives removed, a mesh sole given spheres at its points."""
    kinds = {getattr(mujoco.mjtGeom, f"mjGEOM_{k.upper()}") for k in CONTACT_GEOMS}
    for geom in list(spec.geoms):
        if geom.parent.name not in links or geom.type not in kinds:
            spec.delete(geom)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    bodies = {b.name: b for b in spec.bodies}
    for link, (points, up) in soles.items():
        if link in bodies and not any(g.parent.name == link for g in spec.geoms):
            for point in points:
                bodies[link].add_geom(
                    type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[SOLE_SPHERE, 0, 0], pos=point + SOLE_SPHERE * up
                )
    if not spec.geoms:
        raise ExciteError("constraints.zmp.support_links", "MuJoCo finds no sphere, box or capsule on these links")


def _environment(mujoco, spec, constraints: ConstraintsConfig) -> None:
    """The config's environment shapes as MuJoCo geoms of the world, named after them."""
    environment = constraints.environment
    for shape in environment.shapes if environment else []:
        g = mujoco.mjtGeom
        if shape.type == "half_space":
            normal = np.asarray(shape.normal, float) / np.linalg.norm(shape.normal)
            quat = np.zeros(4)
            mujoco.mju_quatZ2Vec(quat, normal)
            spec.worldbody.add_geom(name=shape.name, type=g.mjGEOM_PLANE, size=[5, 5, 0.1], pos=shape.point, quat=quat)
        elif shape.type == "sphere":
            spec.worldbody.add_geom(name=shape.name, type=g.mjGEOM_SPHERE, size=[shape.radius, 0, 0], pos=shape.centre)
        elif shape.type == "capsule":
            spec.worldbody.add_geom(
                name=shape.name, type=g.mjGEOM_CAPSULE, size=[shape.radius, 0, 0], fromto=[*shape.start, *shape.end]
            )
        else:
            quat = np.zeros(4)
            mujoco.mju_euler2Quat(quat, np.asarray(shape.rpy, float), "XYZ")
            half = [s / 2 for s in shape.size]
            spec.worldbody.add_geom(name=shape.name, type=g.mjGEOM_BOX, size=half, pos=shape.centre, quat=quat)


def _lowest(mujoco, model, locked: dict[str, float]) -> float:
    """The height [m] of the soles' lowest point, the robot posed at its locked values, the root at the
    origin."""
    data = mujoco.MjData(model)
    pose(model, data, locked)
    mujoco.mj_forward(model, data)
    return min(data.geom_xpos[g, 2] - _depth(mujoco, model, data, g) for g in range(model.ngeom))


def joint_names(model) -> list[str]:
    """The names of the model's hinge and slide joints (not the free joint), in order."""
    return [model.joint(j).name for j in range(model.njnt) if model.jnt_type[j] in (2, 3)]


def pose(model, data, values: dict[str, float]) -> None:
    """A free root at the world origin, at rest, and the named joints at their values [rad]."""
    data.qpos[:] = model.qpos0
    data.qvel[:] = 0.0
    for j in range(model.njnt):
        if model.jnt_type[j] == 0:  # free: the origin, the unit quaternion
            data.qpos[model.jnt_qposadr[j] : model.jnt_qposadr[j] + FREE_QPOS] = [0, 0, 0, 1, 0, 0, 0]
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
