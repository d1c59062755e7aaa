"""The identified model as MuJoCo reads it (MJCF), built with MuJoCo's own model editing (``MjSpec``).

MuJoCo compiles the URDF itself; the spec is then edited: each body of the identification model
(a moving joint's child link, everything locked or fixed to it merged in, see ``Robot``) gets the
physically consistent fit's inertia (mass, centre of mass, inertia about it in the link's axes: the
body frame MuJoCo gives a URDF link), the links merged into it none, and the joints that are not
active are removed, which welds their child at the locked value (MuJoCo then fuses it into its
parent, ``compiler.fusestatic``). The joint-level effects MuJoCo holds go to the active joints:
armature → ``armature`` (reflected rotor inertia, on the mass matrix diagonal), viscous friction →
``damping`` and Coulomb friction → ``frictionloss`` with ``solreffriction`` at its stiffest
(MuJoCo documentation, XML reference: joint; Computation: friction loss).
Every other effect (offsets, asymmetric, Stribeck, held, load-dependent and position-dependent terms,
a motor turning with several joints) is listed, not written: MuJoCo has no joint field for it. Each
active joint gets a torque motor (``<motor>``, ``ctrl`` in Nm, limited to the URDF's effort).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from excite_cli.atomic import MARK, atomic_path
from excite_cli.dynamics.mjcf_compiled import is_mjcf
from excite_cli.dynamics.robot import Robot
from excite_cli.dynamics.urdf_meshes import mesh_path
from excite_cli.errors import ExciteError
from excite_cli.identification.effects import Term
from excite_cli.identification.reporting.urdf_out import merged_links

#: The effects an MJCF joint holds: effect → the joint's attribute.
JOINT_FIELDS = {"armature": "armature", "viscous": "damping", "coulomb": "frictionloss"}
#: Mesh formats MuJoCo reads; a URDF's other meshes (Collada) are left out of the MJCF.
MESH_FORMATS = (".stl", ".obj", ".msh")
#: Smallest mass [kg] and principal inertia [kg·m²] written for a moving body: MuJoCo refuses a moving
#: body at or below mjMINVAL (1e-15), which a body the data did not excite may be given.
SMALLEST_MASS, SMALLEST_INERTIA = 1e-6, 1e-9
#: Time constant of the friction loss constraint (``solreffriction``), in timesteps: MuJoCo's safe
#: minimum (it clamps shorter ones). Its inverse-dynamics friction opposes q̈ + b q̇ with b ∝ 1/time
#: constant, so MuJoCo's default 0.02 s blurs Coulomb friction over ~0.1 rad/s: on the real Panda run
#: its validation error was 7.15 % against 6.41 % with this (excite's model with the same effects: 6.42 %).
FRICTION_TIMESTEPS = 2.0


@dataclass
class MjcfModel:
    """What ``write_mjcf`` wrote.

    Attributes:
        path: the MJCF file.
        joints: (n,) the active joints, MuJoCo's degrees of freedom in this order.
        fields: {(joint, attribute): value} written to the joints (armature [kg·m²], damping
            [Nm·s/rad], frictionloss [Nm]).
        written: (term, coefficient) of each effect written to a joint field.
        unwritten: (term, coefficient, value, reason) of each effect MuJoCo has no field for.
        notes: what else the file differs in from the URDF, in words (joints welded, bodies bounded,
            meshes left out).
    """

    path: Path
    joints: list[str]
    fields: dict[tuple[str, str], float] = field(default_factory=dict)
    written: list[tuple[Term, str]] = field(default_factory=list)
    unwritten: list[tuple[Term, str, float, str]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def import_mujoco():
    """The ``mujoco`` module.

    Raises:
        ExciteError: MuJoCo is not installed (it is an optional dependency).
    """
    try:
        import mujoco
    except ImportError:
        raise ExciteError(
            "mjcf_out", "needs MuJoCo, which is not installed", expected="`pip install mujoco` (the [mujoco] extra)"
        ) from None
    return mujoco


def resolve_meshes(spec, urdf: Path, package_dirs: list[str], notes: list[str]) -> None:
    """Give every mesh an absolute file name (:func:`~excite_cli.dynamics.urdf_meshes.mesh_path`); a
    mesh that is missing or in a format MuJoCo does not read is removed with the geoms using it."""
    for mesh in list(spec.meshes):
        name = mesh.file
        found = mesh_path(name, urdf, package_dirs)
        found = found.resolve() if found is not None and found.is_file() else None
        if found is not None and found.suffix.lower() in MESH_FORMATS:
            mesh.file = str(found)
            continue
        for geom in [g for g in spec.geoms if g.meshname == mesh.name]:
            spec.delete(geom)
        spec.delete(mesh)
        why = "not found" if found is None else "a format MuJoCo cannot read"
        notes.append(f"collision mesh {name} left out ({why})")


def urdf_spec(urdf: Path):
    """The ``mujoco`` module and MuJoCo's spec (``MjSpec``) of the URDF at ``urdf``, its bodies keeping
    the URDF's inertias (not MuJoCo's from the geometry).

    Raises:
        ExciteError: MuJoCo is missing or cannot read the URDF.
    """
    mujoco = import_mujoco()
    try:
        spec = mujoco.MjSpec.from_file(str(urdf))
    except ValueError as exc:
        raise ExciteError("robot.urdf", f"MuJoCo cannot read {urdf}: {exc}") from None
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    return mujoco, spec


def weld_joints(mujoco, spec, active: list[str], locked: dict[str, float], notes: list[str]) -> None:
    """Remove every joint of ``spec`` not in ``active`` (and the equality constraints on it, a URDF
    <mimic>), turning its child body by the joint's locked value [rad or m] (0 unless ``locked`` says);
    the free joint of a floating root is kept. What was welded is added to ``notes``."""
    welded = [j for j in spec.joints if j.name not in active and j.type != mujoco.mjtJoint.mjJNT_FREE]
    names = {j.name for j in welded}
    for equality in [e for e in spec.equalities if e.name1 in names or e.name2 in names]:
        spec.delete(equality)
    for joint in welded:
        body, value = joint.parent, locked.get(joint.name, 0.0)
        if value and joint.type == mujoco.mjtJoint.mjJNT_HINGE:
            turn = np.zeros(4)
            mujoco.mju_axisAngle2Quat(turn, np.asarray(joint.axis, float), value)
            quat = np.zeros(4)
            mujoco.mju_mulQuat(quat, np.asarray(body.quat, float), turn)
            body.quat = quat
        elif value and joint.type == mujoco.mjtJoint.mjJNT_SLIDE:
            shift = np.zeros(3)
            mujoco.mju_rotVecQuat(shift, np.asarray(joint.axis, float) * value, np.asarray(body.quat, float))
            body.pos = np.asarray(body.pos, float) + shift
        spec.delete(joint)
    if welded:
        notes.append(f"welded (not active, held as in the identification): {', '.join(sorted(names))}")


def _inertias(spec, robot: Robot, standard: np.ndarray, notes: list[str]) -> None:
    """Each body's identified inertia (10 standard parameters per body) on its MuJoCo body, none on
    the links merged into it; a body below MuJoCo's smallest mass or inertia is bounded, with a note."""
    for i, (name, merged) in enumerate(merged_links(robot).items()):
        inertia = pin.Inertia.FromDynamicParameters(standard[10 * i : 10 * i + 10])
        mass, com, I = inertia.mass, inertia.lever, inertia.inertia.copy()
        if not np.all(np.isfinite(com)):  # no mass: the first moments are 0 too (a consistent fit)
            com, I = np.zeros(3), np.asarray(standard[10 * i + 4 : 10 * i + 10])[[0, 1, 3, 1, 2, 4, 3, 4, 5]]
            I = I.reshape(3, 3)
        if mass < SMALLEST_MASS or np.linalg.eigvalsh(I).min() < SMALLEST_INERTIA:
            mass = max(mass, SMALLEST_MASS)
            I = I + SMALLEST_INERTIA * np.eye(3)
            notes.append(
                f"{name}: mass or inertia below MuJoCo's smallest, raised to {mass:g} kg, +{SMALLEST_INERTIA:g} kg·m²"
            )
        _set_inertial(spec.body(name), mass, com, I)
        for other in merged:
            if spec.body(other) is not None:
                _set_inertial(spec.body(other), 0.0, np.zeros(3), None)


def _set_inertial(body, mass: float, com: np.ndarray, I: np.ndarray | None) -> None:
    """``body``'s inertial: mass [kg], centre of mass (3,) [m], inertia about it (3, 3) [kg·m²] or
    None (a massless link merged into a body)."""
    body.explicitinertial = True
    body.mass, body.ipos, body.iquat = mass, com, [1.0, 0.0, 0.0, 0.0]
    if I is None:
        body.fullinertia, body.inertia = np.full(6, np.nan), np.zeros(3)
    else:  # an MJCF's diagonal inertia gives way (MuJoCo takes one of the two)
        body.fullinertia, body.inertia = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]], np.zeros(3)


def _joint_fields(spec, robot: Robot, effects: list[tuple[Term, str, float]], model: MjcfModel) -> None:
    """The effects with a joint field on the active joints (every such field 0 otherwise)."""
    for name in robot.joint_names:
        joint = spec.joint(name)
        joint.armature, joint.frictionloss = 0.0, 0.0
        joint.damping = np.zeros_like(np.asarray(joint.damping, float))
    for term, coefficient, value in effects:
        attribute = JOINT_FIELDS.get(term.effect) if term.coupling is None else None
        if attribute is None:
            why = "a motor turning with several joints" if term.coupling is not None else "no MuJoCo joint field"
            model.unwritten.append((term, coefficient, value, why))
        elif value < 0:
            model.unwritten.append((term, coefficient, value, f"negative, MuJoCo's {attribute} cannot be"))
        else:
            joint, name = spec.joint(robot.joint_names[term.joint]), robot.joint_names[term.joint]
            if attribute == "damping":
                damping = np.asarray(joint.damping, float).copy()
                damping[0] = value
                joint.damping = damping
            else:
                setattr(joint, attribute, value)
            if attribute == "frictionloss":  # the stiffest friction constraint MuJoCo keeps stable
                joint.solref_friction = [FRICTION_TIMESTEPS * spec.option.timestep, 1.0]
            model.fields[(name, attribute)] = value
            model.written.append((term, coefficient))


def _motors(mujoco, spec, robot: Robot) -> None:
    """A torque motor (gear 1, ``ctrl`` in Nm) on each active joint, named after it, its control range
    the URDF's effort limit where the URDF gives one (MuJoCo reads it as the joint's
    ``actuatorfrcrange``), so that the model plays measured or planned torques as they are."""
    for name in robot.joint_names:
        motor = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        limit = np.asarray(spec.joint(name).actfrcrange, float)
        if limit[1] > limit[0]:
            motor.ctrlrange, motor.ctrllimited = limit, mujoco.mjtLimited.mjLIMITED_TRUE


def clear_controls(spec, notes: list[str]) -> None:
    """An MJCF's own actuators, tendons (and their equalities), sensors and keyframes, removed: the
    motors written here replace the actuators, and the rest would name joints that are welded or
    states of another size."""
    kinds = {"actuator": spec.actuators, "tendon": spec.tendons, "sensor": spec.sensors, "keyframe": spec.keys}
    tendons = {t.name for t in spec.tendons}
    for equality in [e for e in spec.equalities if e.name1 in tendons or e.name2 in tendons]:
        spec.delete(equality)
    for kind, elements in kinds.items():
        for element in list(elements):
            spec.delete(element)
        if elements:
            notes.append(f"the file's {kind}s left out ({len(elements)})")


def write_mjcf(
    urdf: Path,
    package_dirs: list[str],
    robot: Robot,
    locked: dict[str, float],
    standard: np.ndarray,
    effects: list[tuple[Term, str, float]],
    target: Path,
) -> MjcfModel:
    """Write the identified model as MJCF to ``target`` (atomically), compiled by MuJoCo first.

    Args:
        urdf: the URDF or MJCF the identification used; package_dirs: folders its ``package://``
            meshes are in (an MJCF's: its meshdir).
        robot: the identification model (active joints, bodies, merged links).
        locked: ``robot.locked_joints`` {joint: value [rad or m]}.
        standard: (p,) the physically consistent standard parameters φ, 10 per body [kg, kg·m, kg·m²].
        effects: (term, coefficient, value) of the identified effects (consistent fit).

    Raises:
        ExciteError: MuJoCo is missing, cannot read the URDF or refuses the model; the file cannot be
            written.
    """
    mujoco, spec = urdf_spec(urdf)
    model = MjcfModel(Path(target), list(robot.joint_names))
    if is_mjcf(urdf):  # meshes are in the file's meshdir
        package_dirs = [*package_dirs, str(urdf.parent / spec.meshdir)]
        clear_controls(spec, model.notes)
    resolve_meshes(spec, urdf, package_dirs, model.notes)
    weld_joints(mujoco, spec, robot.joint_names, locked, model.notes)
    _inertias(spec, robot, standard, model.notes)
    _joint_fields(spec, robot, effects, model)
    _motors(mujoco, spec, robot)
    try:
        spec.compile()
    except ValueError as exc:
        raise ExciteError("mjcf_out", f"MuJoCo refuses the identified model: {exc}") from None
    with atomic_path(Path(target), "mjcf_out") as tmp:
        Path(tmp).write_text(f"<!-- {MARK} identify -->\n{spec.to_xml()}", encoding="utf-8")
    return model
