"""A robot described in MJCF (MuJoCo's XML, as MuJoCo Menagerie ships robots) as MuJoCo reads it:
compiled by MuJoCo's own compiler (``<include>``, ``<default>`` classes, ``<frame>`` elements, angle
units, inertias from geoms, all resolved as MuJoCo resolves them), then handed to pinocchio body by
body.

From the compiled ``mjModel``: each body's placement in its parent (``body_pos``, ``body_quat``),
its joints (hinge: revolute, slide: prismatic, ball: spherical, each through its ``jnt_pos`` along
``jnt_axis``; a body without a joint is welded to its parent's), its inertia (``body_mass`` at
``body_ipos``, principal moments ``body_inertia`` in ``body_iquat``), the joint ranges
(``jnt_range`` where ``jnt_limited``), the armature (``dof_armature``), and the joint torque limits
from the actuators (MuJoCo's actuation model, mujoco.readthedocs.io "Actuation model": a joint
transmission's torque is ``gear`` × the actuator force; the force is clamped to ``forcerange`` when
``forcelimited``; a ``motor``'s force is its control, clamped to ``ctrlrange``; ``actuatorfrcrange``
bounds the sum at the joint). A free joint of a root body is the floating base
(``robot.floating_base``), or welded where the base is. Geoms that collide (``contype`` or
``conaffinity``) of the robot's bodies are the collision geometry; those of ``<worldbody>`` itself
(a floor) are the world's.

The file's joint ``damping`` and ``frictionloss`` are not the rigid body's: they are said in a
warning (identify finds them as viscous and Coulomb friction), not built in. Its equality constraints
(joint and tendon couplings, closed chains) are checked in :mod:`~excite_cli.dynamics.mjcf_equalities`.
MJCF has no velocity limits and a hinge
may have no range: ``limits.velocity`` and ``robot.joint_ranges`` give them
(:mod:`~excite_cli.constraints.joint_limits` asks, naming the joint).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from excite_cli.dynamics.mjcf_compiled import compiled
from excite_cli.dynamics.mjcf_compiled import mjcf_name as _name
from excite_cli.dynamics.mjcf_equalities import check_mjcf, mjcf_couplings
from excite_cli.dynamics.source import RobotSource
from excite_cli.errors import ExciteError, ExciteWarning

#: The name of the free-flyer root joint of a floating base.
ROOT_JOINT = "root_joint"
FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3  # mjtJoint
SPHERE, CAPSULE, ELLIPSOID, CYLINDER, BOX, MESH = 2, 3, 4, 5, 6, 7  # mjtGeom
MOTOR_GAIN, NO_BIAS, JOINT_TRANSMISSION = 0, 0, 0  # mjtGain fixed, mjtBias none, mjtTrn joint


def _placement(quat: np.ndarray, pos: np.ndarray) -> pin.SE3:
    return pin.SE3(pin.Quaternion(*quat).matrix(), np.array(pos, dtype=float))


def _joint_model(kind: int, axis: np.ndarray):
    unit = {tuple(np.eye(3)[k]): k for k in range(3)}.get(tuple(np.round(axis, 12)))
    if kind == HINGE:
        return (
            (pin.JointModelRX, pin.JointModelRY, pin.JointModelRZ)[unit]()
            if unit is not None
            else (pin.JointModelRevoluteUnaligned(*axis))
        )
    if kind == SLIDE:
        return (
            (pin.JointModelPX, pin.JointModelPY, pin.JointModelPZ)[unit]()
            if unit is not None
            else (pin.JointModelPrismaticUnaligned(*axis))
        )
    return pin.JointModelSpherical()


def _add_joints(mj, model: pin.Model, b: int, parent: tuple[int, pin.SE3], floating: bool) -> tuple[int, pin.SE3]:
    """Body ``b``'s joints added after ``parent`` (joint id, body placement in it); its own (joint id,
    placement of the body frame in that joint)."""
    joint, placement = parent
    joints = range(mj.body_jntadr[b], mj.body_jntadr[b] + mj.body_jntnum[b])
    if any(mj.jnt_type[j] == FREE for j in joints):
        if mj.body_parentid[b] != 0 or mj.body_jntnum[b] > 1:
            raise ExciteError("robot.urdf", f"body '{_name(mj, 'body', b)}' has a free joint but is not a root body")
        if floating and model.existJointName(ROOT_JOINT):
            raise ExciteError(
                "robot.floating_base",
                f"body '{_name(mj, 'body', b)}' has a free joint of its own: the file holds more than one free "
                "body, and excite's floating base is one root",
                True,
                "one free body (the robot's root); a loose object belongs in constraints.environment",
            )
        if floating:
            root = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), ROOT_JOINT)
            model.addJointFrame(root, -1)
            return root, pin.SE3.Identity()
        return 0, pin.SE3.Identity()
    here = placement * _placement(mj.body_quat[b], mj.body_pos[b])
    last = np.zeros(3)
    for j in joints:
        offset = here * pin.SE3(np.eye(3), mj.jnt_pos[j] - last)
        joint = model.addJoint(joint, _joint_model(mj.jnt_type[j], mj.jnt_axis[j]), offset, _name(mj, "joint", j))
        model.addJointFrame(joint, -1)
        here, last = pin.SE3.Identity(), mj.jnt_pos[j].copy()
    return joint, here * pin.SE3(np.eye(3), -last)


def _limits(mj, model: pin.Model, j: int, torques: dict[str, float]) -> None:
    """Joint ``j``'s range, armature, torque limit (``torques``, else inf) and velocity limit (MJCF has
    none: inf) on ``model``."""
    name = _name(mj, "joint", j)
    jid = model.getJointId(name)
    q, v, nv = model.idx_qs[jid], model.idx_vs[jid], model.nvs[jid]
    if mj.jnt_type[j] in (HINGE, SLIDE):
        low, high = mj.jnt_range[j] if mj.jnt_limited[j] else (-np.inf, np.inf)
        model.lowerPositionLimit[q], model.upperPositionLimit[q] = low, high
    dofs = slice(mj.jnt_dofadr[j], mj.jnt_dofadr[j] + nv)
    model.armature[v : v + nv] = mj.dof_armature[dofs]
    model.velocityLimit[v : v + nv] = np.inf
    model.effortLimit[v : v + nv] = torques.get(name, np.inf)


def mjcf_model(path: Path, floating: bool = False) -> pin.Model:
    """pinocchio's model of the MJCF at ``path`` as MuJoCo compiles it (module docstring), with a
    free-flyer root joint ``root_joint`` when ``floating``.

    Raises:
        ExciteError: (``robot.urdf``) see :func:`compiled`; a free joint below the root.
    """
    mj = compiled(path, meshes=False)
    model = pin.Model()
    model.name = Path(path).stem
    placed: dict[int, tuple[int, pin.SE3]] = {0: (0, pin.SE3.Identity())}
    for b in range(1, mj.nbody):
        joint, placement = _add_joints(mj, model, b, placed[mj.body_parentid[b]], floating)
        placed[b] = (joint, placement)
        inertia = pin.Inertia(
            float(mj.body_mass[b]),
            np.array(mj.body_ipos[b], dtype=float),
            (R := pin.Quaternion(*mj.body_iquat[b]).matrix()) @ np.diag(mj.body_inertia[b]) @ R.T,
        )
        model.appendBodyToJoint(joint, inertia, placement)
        model.addBodyFrame(_name(mj, "body", b), joint, placement, -1)
    torques = joint_torque_limits(mj)
    for j in range(mj.njnt):
        if mj.jnt_type[j] != FREE:
            _limits(mj, model, j, torques)
    _say_losses(mj, Path(path).name)
    return model


def joint_torque_limits(mj) -> dict[str, float]:
    """{joint: largest torque [N·m] (force [N] of a slide)} the actuators of a joint transmission can
    give (module docstring); joints without a bounded actuator are left out (their torque unchecked)."""
    limits: dict[str, float] = {}
    for a in range(mj.nu):
        if mj.actuator_trntype[a] != JOINT_TRANSMISSION:
            continue
        gear, bounds = abs(mj.actuator_gear[a][0]), []
        if mj.actuator_forcelimited[a]:
            bounds.append(np.abs(mj.actuator_forcerange[a]).max())
        motor = mj.actuator_gaintype[a] == MOTOR_GAIN and mj.actuator_biastype[a] == NO_BIAS
        if motor and mj.actuator_ctrllimited[a]:
            bounds.append(abs(mj.actuator_gainprm[a][0]) * np.abs(mj.actuator_ctrlrange[a]).max())
        if bounds:
            name = _name(mj, "joint", mj.actuator_trnid[a][0])
            limits[name] = limits.get(name, 0.0) + gear * min(bounds)
    for j in range(mj.njnt):
        if mj.jnt_actfrclimited[j]:
            name = _name(mj, "joint", j)
            limits[name] = min(limits.get(name, np.inf), float(np.abs(mj.jnt_actfrcrange[j]).max()))
    return {k: float(v) for k, v in limits.items()}


def _say_losses(mj, file_name: str) -> None:
    """One warning naming the joints whose damping or frictionloss the file gives (module docstring)."""
    said = []
    for what, values, unit in (("damping", mj.dof_damping, "N·m·s/rad"), ("frictionloss", mj.dof_frictionloss, "N·m")):
        joints = [f"{_name(mj, 'joint', mj.dof_jntid[d])} {values[d]:.3g}" for d in range(mj.nv) if values[d] > 0]
        if joints:
            said.append(f"{what} [{unit}] ({', '.join(joints)})")
    if said:
        warnings.warn(
            f"robot.urdf: {file_name} gives joint {' and '.join(said)}, which excite's model (rigid bodies and "
            "armature) leaves out: identify finds them as viscous and Coulomb friction",
            ExciteWarning,
            stacklevel=3,
        )


def _shape(mj, g: int):
    size, kind = mj.geom_size[g], mj.geom_type[g]
    if kind == SPHERE:
        return coal.Sphere(size[0])
    if kind == CAPSULE:
        return coal.Capsule(size[0], 2 * size[1])
    if kind == CYLINDER:
        return coal.Cylinder(size[0], 2 * size[1])
    if kind == BOX:
        return coal.Box(*(2 * size))
    if kind == ELLIPSOID:
        return coal.Ellipsoid(*size)
    if kind == MESH:
        m = mj.geom_dataid[g]
        vertices = mj.mesh_vert[mj.mesh_vertadr[m] : mj.mesh_vertadr[m] + mj.mesh_vertnum[m]]
        faces = mj.mesh_face[mj.mesh_faceadr[m] : mj.mesh_faceadr[m] + mj.mesh_facenum[m]]
        mesh = coal.BVHModelOBBRSS()
        mesh.beginModel(len(faces), len(vertices))
        mesh.addVertices(np.asarray(vertices, dtype=float))
        mesh.addTriangles(np.asarray(faces, dtype=np.int64))
        mesh.endModel()
        return mesh
    return None  # a plane or height field on a body: not a shape the robot's collisions take


def mjcf_geometry(model: pin.Model, path: Path) -> pin.GeometryModel:
    """The colliding geoms of the MJCF's bodies (not ``<worldbody>``'s own) on ``model`` (built by
    :func:`mjcf_model` from the same file, full or reduced), each on its body's frame."""
    mj = compiled(path)
    geometry = pin.GeometryModel()
    for g in range(mj.ngeom):
        body = mj.geom_bodyid[g]
        shape = _shape(mj, g) if body > 0 and (mj.geom_contype[g] or mj.geom_conaffinity[g]) else None
        if shape is None:
            continue
        index = model.getFrameId(_name(mj, "body", body), pin.FrameType.BODY)
        frame = model.frames[index]
        placement = frame.placement * _placement(mj.geom_quat[g], mj.geom_pos[g])
        name = mj.geom(g).name or f"{_name(mj, 'body', body)}_geom{g}"
        geometry.addGeometryObject(pin.GeometryObject(name, frame.parentJoint, index, placement, shape))
    return geometry


@dataclass(frozen=True)
class MjcfSource(RobotSource):
    """An MJCF as MuJoCo compiles it (module docstring; :class:`~excite_cli.dynamics.source.RobotSource`)."""

    @property
    def kind(self) -> str:
        return "MJCF"

    def model(self, floating: bool = False) -> pin.Model:
        """See :func:`mjcf_model`."""
        return mjcf_model(self.path, floating)

    def geometry(self, model: pin.Model) -> pin.GeometryModel:
        """See :func:`mjcf_geometry`."""
        return mjcf_geometry(model, self.path)

    def couplings(self) -> dict[str, tuple[str, str]]:
        """See :func:`mjcf_couplings`."""
        return mjcf_couplings(self.path)

    def check(self, active: list[str], locked: list[str] = (), physical: bool = True) -> list[str]:
        """The joint couplings (:func:`check_mjcf`); MuJoCo's compiler has checked the bodies."""
        check_mjcf(self.path, list(active), list(locked))
        return []

    def named_states(self) -> dict[str, dict[str, float]]:
        """The keyframes (``<keyframe><key qpos>``), hinge and slide joints only (a free joint's pose is
        left out: excite holds the base at the identity)."""
        mj = compiled(self.path, meshes=False)
        hinges = [j for j in range(mj.njnt) if mj.jnt_type[j] in (HINGE, SLIDE)]
        return {
            _name(mj, "key", k): {_name(mj, "joint", j): float(mj.key_qpos[k][mj.jnt_qposadr[j]]) for j in hinges}
            for k in range(mj.nkey)
        }

    def free_root(self) -> str | None:
        """The first free joint of a root body, or None."""
        mj = compiled(self.path, meshes=False)
        free = [j for j in range(mj.njnt) if mj.jnt_type[j] == FREE and mj.body_parentid[mj.jnt_bodyid[j]] == 0]
        return _name(mj, "joint", free[0]) if free else None
