"""Where a robot's file is (inside the installed example-robot-data package, or a file beside the
config), and its :class:`~excite_cli.dynamics.source.RobotSource`: a URDF with the SRDF beside it, or an
MJCF, told apart by the file's root element."""

from __future__ import annotations

from importlib import metadata
from pathlib import Path

from excite_cli.config import RobotConfig, resolve_path
from excite_cli.dynamics.mjcf_compiled import is_mjcf
from excite_cli.dynamics.mjcf_source import MjcfSource
from excite_cli.dynamics.source import RobotSource
from excite_cli.dynamics.urdf_meshes import package_folders
from excite_cli.dynamics.urdf_source import UrdfSource
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


def open_source(path: Path, package_dirs: list[str] = ()) -> RobotSource:
    """The :class:`~excite_cli.dynamics.source.RobotSource` of the robot file at ``path``: an MJCF (its
    root element ``<mujoco>``), else a URDF (its named postures the SRDF's beside it,
    :func:`~excite_cli.dynamics.srdf.srdf_beside`, if any)."""
    return (MjcfSource if is_mjcf(path) else UrdfSource)(Path(path), tuple(package_dirs))


def robot_source(cfg: RobotConfig, folder: Path | None = None) -> RobotSource:
    """The :class:`~excite_cli.dynamics.source.RobotSource` of a ``robot`` section (:func:`resolve_urdf`).

    Raises:
        ExciteError: see :func:`resolve_urdf`.
    """
    return open_source(*resolve_urdf(cfg, folder))
