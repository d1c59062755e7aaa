"""Where a robot's URDF is (inside the installed example-robot-data package, or a file beside the config),
and pinocchio's model of it."""

from __future__ import annotations

from importlib import metadata
from pathlib import Path

import pinocchio as pin

from excite_cli.config import RobotConfig, resolve_path
from excite_cli.dynamics.urdf_meshes import package_folders
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


def urdf_model(path: Path, *root_joint) -> pin.Model:
    """pinocchio's model of the URDF at ``path`` (with ``root_joint``, e.g. a free flyer, under its root).

    Raises:
        ExciteError: (``robot.urdf``) a file urdfdom or pinocchio cannot make a model of (an unknown
            joint type, a missing attribute), in one line.
    """
    try:
        return pin.buildModelFromUrdf(str(path), *root_joint)
    except (RuntimeError, ValueError) as exc:
        raise ExciteError("robot.urdf", f"cannot read {path}: {' '.join(str(exc).split())[:300]}") from None
