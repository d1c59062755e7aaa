"""Where a robot's file is (inside the installed example-robot-data package, or a file beside the config),
and pinocchio's model of it: a URDF, or an MJCF (:mod:`~excite_cli.dynamics.mjcf_source`).

A URDF's continuous joints are read as revolute joints without a range (pinocchio would give each
two configuration coordinates, cos and sin, which no Fourier series of an angle moves):
``robot.joint_ranges`` gives such a joint the range it may move in, and narrows any other's.
"""

from __future__ import annotations

from importlib import metadata
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pinocchio as pin

from excite_cli.config import RobotConfig, resolve_path
from excite_cli.dynamics.mjcf_source import is_mjcf, mjcf_couplings, mjcf_geometry, mjcf_model
from excite_cli.dynamics.urdf_checks import urdf_couplings
from excite_cli.dynamics.urdf_meshes import collision_geometry, package_folders
from excite_cli.errors import ExciteError
from excite_cli.inputs import input_file


def example_robot_data_root() -> Path:
    """Folder ``share`` of the installed example-robot-data package (holds ``example-robot-data/robots``).

    Raises:
        ExciteError: the package is not installed.
    """
    share = installed_share()
    if share is None:
        raise ExciteError("robot.source", "example-robot-data is not installed (run `make install`)")
    return share


def installed_share() -> Path | None:
    """example-robot-data's ``share`` folder, or None where the package is not installed."""
    try:
        dist = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        return None
    return Path(dist.locate_file("cmeel.prefix/share")).resolve()


def resolve_urdf(cfg: RobotConfig, folder: Path | None = None) -> tuple[Path, list[str]]:
    """The URDF file named by ``robot.urdf`` and the package folders its meshes are found in:
    ``robot.package_dirs``, the URDF's folder and the one above it, example-robot-data's (where
    installed: a URDF of one's own needs nothing of it), and those
    :func:`~excite_cli.dynamics.urdf_meshes.package_folders` adds.

    Args:
        cfg: the ``robot`` section.
        folder: the config file's folder, which a relative ``urdf`` with ``source: file`` is in.

    Raises:
        ExciteError: the file does not exist, is a folder, a FIFO or a device (:func:`~excite_cli.inputs.input_file`),
            or ``source: example-robot-data`` without that package installed.
    """
    if cfg.source == "example-robot-data":
        share = example_robot_data_root()
        path = share / "example-robot-data" / "robots" / cfg.urdf
        dirs = [str(share)]
    else:
        path = resolve_path(cfg.urdf, folder)
        share = installed_share()
        dirs = [str(path.parent), str(path.parent.parent)] + ([str(share)] if share is not None else [])
    dirs = [str(resolve_path(d, folder)) for d in cfg.package_dirs] + dirs  # the user's folders first
    path = input_file(path, "robot.urdf", "URDF")
    return path, package_folders(path, dirs)


def _continuous_as_revolute(path: Path) -> tuple[str, list[str]]:
    """The URDF text at ``path`` with each continuous joint made revolute, and those joints' names."""
    root = ElementTree.parse(path).getroot()
    names = []
    for joint in root.iter("joint"):
        if joint.get("type") == "continuous":
            joint.set("type", "revolute")
            limit = joint.find("limit")
            limit = ElementTree.SubElement(joint, "limit") if limit is None else limit
            limit.attrib.update({k: limit.get(k, "0") for k in ("effort", "velocity")}, lower="0", upper="0")
            names.append(joint.get("name"))
    return ElementTree.tostring(root, encoding="unicode"), names


def robot_model(path: Path, floating: bool = False) -> pin.Model:
    """pinocchio's model of the URDF or MJCF at ``path``, with a free-flyer root joint when ``floating``;
    a URDF's continuous joints are revolute with limits ±inf (module docstring).

    Raises:
        ExciteError: (``robot.urdf``) a file urdfdom or pinocchio cannot make a model of (an unknown
            joint type, a missing attribute), in one line.
    """
    if is_mjcf(path):
        return mjcf_model(path, floating)
    root = [pin.JointModelFreeFlyer()] if floating else []
    try:
        text, continuous = _continuous_as_revolute(path)
        model = pin.buildModelFromXML(text, *root) if continuous else pin.buildModelFromUrdf(str(path), *root)
    except (RuntimeError, ValueError, ElementTree.ParseError) as exc:
        raise ExciteError("robot.urdf", f"cannot read {path}: {' '.join(str(exc).split())[:300]}") from None
    for name in continuous:
        k = model.idx_qs[model.getJointId(name)]
        model.lowerPositionLimit[k], model.upperPositionLimit[k] = -np.inf, np.inf
    return model


def robot_geometry(model: pin.Model, path: Path, package_dirs: list[str]) -> pin.GeometryModel:
    """The collision geometry of the URDF or MJCF at ``path`` for its ``model``.

    Raises:
        ExciteError: see :func:`~excite_cli.dynamics.urdf_meshes.collision_geometry`, :func:`mjcf_geometry`.
    """
    return mjcf_geometry(model, path) if is_mjcf(path) else collision_geometry(model, path, package_dirs)


def joint_couplings(path: Path) -> dict[str, tuple[str, str]]:
    """{follower: (leader, how, in words)} of the joints of the URDF or MJCF at ``path`` that follow
    another (a ``<mimic>``, a joint equality)."""
    return mjcf_couplings(path) if is_mjcf(path) else urdf_couplings(ElementTree.parse(path).getroot())


def apply_joint_ranges(model: pin.Model, ranges: dict[str, tuple[float, float]], file_name: str) -> None:
    """Set the position limits of the joints ``ranges`` names ({joint: (lower, upper)} [rad or m]).

    Raises:
        ExciteError: (``robot.joint_ranges.<joint>``) an unknown or multi-DoF joint, lower ≥ upper, or a
            range reaching past the file's own limits.
    """
    for name, (lower, upper) in ranges.items():
        field = f"robot.joint_ranges.{name}"
        if not model.existJointName(name) or model.joints[model.getJointId(name)].nq != 1:
            raise ExciteError(field, f"'{name}' is not a 1-DoF joint of {file_name}")
        k = model.idx_qs[model.getJointId(name)]
        lo, hi = model.lowerPositionLimit[k], model.upperPositionLimit[k]
        if not lower < upper:
            raise ExciteError(field, f"[{lower:g}, {upper:g}] is empty", [lower, upper], "lower < upper")
        if lower < lo or upper > hi:
            raise ExciteError(
                field,
                f"[{lower:g}, {upper:g}] reaches past the limits in {file_name}, [{lo:g}, {hi:g}]",
                [lower, upper],
                "a range inside the file's (it narrows a joint's range, or gives one to a joint without)",
            )
        model.lowerPositionLimit[k], model.upperPositionLimit[k] = lower, upper
