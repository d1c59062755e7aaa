"""A robot described in MJCF (MuJoCo's XML, as MuJoCo Menagerie ships robots), read by pinocchio's own
MJCF parser: joints and their ranges (in MuJoCo's angle unit: degrees unless ``<compiler
angle="radian">``), inertias (from the geoms where a body has no ``<inertial>``, as MuJoCo computes
them), effort limits from ``actuatorfrcrange``, and the collision geometry from the geoms.

What the parser leaves out is refused rather than dropped: a joint of the file missing from the model
(pinocchio skips bodies nested in a ``<frame>`` element, so a whole gripper can vanish with its mass).
An equality constraint that couples two joints (``<equality><joint joint1 joint2>``: joint1 follows
joint2) is a coupling the model does not represent, checked as a URDF ``<mimic>`` is
(:func:`~excite_cli.dynamics.urdf_checks.check_couplings`). MJCF has no velocity limits and a hinge
may have no range: ``limits.velocity`` and ``robot.joint_ranges`` give them
(:mod:`~excite_cli.constraints.joint_limits` asks, naming the joint).
"""

from __future__ import annotations

import warnings
from pathlib import Path
from xml.etree import ElementTree

import pinocchio as pin

from excite_cli.dynamics.urdf_checks import check_couplings
from excite_cli.errors import ExciteError

#: The name of the free-flyer root joint of a floating base.
ROOT_JOINT = "root_joint"


def is_mjcf(path: Path) -> bool:
    """Whether the XML file at ``path`` is an MJCF (its root element is ``<mujoco>``); False for a file
    that is not XML (the URDF reader names that)."""
    try:
        return ElementTree.parse(path).getroot().tag == "mujoco"
    except (ElementTree.ParseError, OSError):
        return False


def _pinocchio_error(path: Path, exc: Exception) -> ExciteError:
    return ExciteError("robot.urdf", f"pinocchio cannot read the MJCF {path.name}: {' '.join(str(exc).split())[:300]}")


def mjcf_model(path: Path, floating: bool = False) -> pin.Model:
    """pinocchio's model of the MJCF at ``path``, with a free-flyer root joint when ``floating``.

    Raises:
        ExciteError: (``robot.urdf``) a file with ``<include>`` elements (:func:`check_includes`), or one
            pinocchio's MJCF parser refuses, in one line.
    """
    check_includes(path)
    try:
        with warnings.catch_warnings():  # the root-joint overload is deprecated for one returning constraints
            warnings.simplefilter("ignore", DeprecationWarning)
            built = (
                pin.buildModelFromMJCF(str(path), pin.JointModelFreeFlyer(), ROOT_JOINT)
                if floating
                else pin.buildModelFromMJCF(str(path))
            )
    except (RuntimeError, ValueError, IndexError) as exc:
        raise _pinocchio_error(path, exc) from None
    return built[0] if isinstance(built, tuple) else built


def check_includes(path: Path) -> None:
    """That the MJCF at ``path`` is one file: pinocchio's MJCF reader does not follow ``<include
    file="...">`` (MuJoCo pastes the included file's elements in its place, the path taken from the
    including file's folder), so what an include holds (a whole arm) would be left out without a word.

    Raises:
        ExciteError: (``robot.urdf``) an include of a file that does not exist, or any include, named.
    """
    try:
        includes = [e.get("file", "") for e in ElementTree.parse(path).getroot().iter("include")]
    except (ElementTree.ParseError, OSError):
        return  # pinocchio's reader names what it cannot read
    for name in includes:
        if not (path.parent / name).is_file():
            raise ExciteError("robot.urdf", f"{path.name} includes {name}, which does not exist", name)
    if includes:
        raise ExciteError(
            "robot.urdf",
            f"{path.name} includes {', '.join(includes)} (<include>), which pinocchio's MJCF reader does not "
            "follow: their bodies and joints would be left out",
            includes[0],
            "the model as one file (MuJoCo writes one: mujoco.MjSpec.from_file(path).to_xml())",
        )


def mjcf_geometry(model: pin.Model, path: Path) -> pin.GeometryModel:
    """The collision geometry of the MJCF at ``path`` (its geoms, meshes found as MuJoCo finds them) for
    ``model``, less the geoms of ``<worldbody>`` itself (a floor, walls: the world's, not the robot's;
    pinocchio's reduced models also lose their frame).

    Raises:
        ExciteError: (``robot.urdf``) a mesh pinocchio or coal cannot find or read.
    """
    try:
        geometry = pin.buildGeomFromMJCF(model, str(path), pin.COLLISION)
    except (RuntimeError, ValueError, IndexError) as exc:
        raise _pinocchio_error(path, exc) from None
    for name in [o.name for o in geometry.geometryObjects if o.parentJoint == 0 and o.parentFrame == 0]:
        geometry.removeGeometryObject(name)
    return geometry


def mjcf_couplings(path: Path) -> dict[str, tuple[str, str]]:
    """{follower: (leader, how)} of the MJCF's joint equality constraints (``joint1`` follows
    ``joint2``; ``how``: the polynomial's coefficients in words)."""
    root = ElementTree.parse(path).getroot()
    out = {}
    for equality in root.iter("equality"):
        for joint in equality.iter("joint"):
            if joint.get("joint1") and joint.get("joint2"):
                out[joint.get("joint1")] = (joint.get("joint2"), f"polycoef {joint.get('polycoef', '0 1 0 0 0')}")
    return out


def check_mjcf(path: Path, model: pin.Model, active: list[str], locked: list[str] = ()) -> None:
    """Every joint of the MJCF at ``path`` is in pinocchio's ``model`` of it, and the ``active`` and
    ``locked`` joints respect its joint couplings (:func:`mjcf_couplings`, checked as a URDF's
    ``<mimic>``).

    Raises:
        ExciteError: (``robot.urdf``) joints the parser left out, named with the likely cause; see
            :func:`~excite_cli.dynamics.urdf_checks.check_couplings`.
    """
    root = ElementTree.parse(path).getroot()
    world = root.find("worldbody")
    declared = [] if world is None else [j.get("name") for j in world.iter("joint")]
    missing = [name for name in declared if name and name not in model.names]
    if missing:
        raise ExciteError(
            "robot.urdf",
            f"pinocchio's MJCF reader leaves out joint(s) {', '.join(missing)} of {path.name} (bodies inside a "
            "<frame> element, which it skips)",
            missing[0],
            "the bodies of those joints directly inside their parent <body> (no <frame>), or the robot's URDF",
        )
    check_couplings(mjcf_couplings(path), active, locked)
