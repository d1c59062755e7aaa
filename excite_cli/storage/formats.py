"""The export's file formats, one record each, without what writes them (the command line's help lists
them at start-up; :mod:`~excite_cli.storage.export` writes them)."""

from dataclasses import dataclass

from excite_cli.errors import ExciteError


@dataclass(frozen=True)
class ExportFormat:
    """One file format of ``export``.

    Attributes:
        name: as ``--format`` takes it.
        ending: the file-name ending (without the dot; "" for a folder).
        controller: a ROS 2 joint_trajectory_controller reads it: checked against the controller's
            rules, τ in its points' effort only when asked (a data file holds τ always).
        folder: written as a folder (a ROS 2 bag).
    """

    name: str
    ending: str
    controller: bool = False
    folder: bool = False

    @property
    def suffix(self) -> str:
        """The ending with its dot, or "" (a folder)."""
        return f".{self.ending}" if self.ending else ""


#: Every format, by name: CSV, NPZ, a FollowJointTrajectory goal as YAML (``ros2``) and a ROS 2 bag,
#: a folder without an ending (``rosbag2``).
FORMATS = {
    f.name: f
    for f in (
        ExportFormat("csv", "csv"),
        ExportFormat("npz", "npz"),
        ExportFormat("ros2", "yaml", controller=True),
        ExportFormat("rosbag2", "", controller=True, folder=True),
    )
}


def export_format(fmt: str, effort: bool = False, approach: float | None = None) -> ExportFormat:
    """The format ``fmt`` names, with ``effort`` (τ as a trajectory's effort) and ``approach`` (when its
    first point comes) asked only of a format a controller reads (a data file holds τ always, and its
    time starts at home).

    Raises:
        ExciteError: another format, or effort or an approach for a data file.
    """
    if fmt not in FORMATS:
        raise ExciteError("format", f"must be one of {', '.join(FORMATS)} (got {fmt!r})")
    readers = " or ".join(name for name, f in FORMATS.items() if f.controller)
    if effort and not FORMATS[fmt].controller:
        raise ExciteError("effort", f"is for the ROS 2 formats; a {fmt} file holds τ always", expected=readers)
    if approach is not None and not FORMATS[fmt].controller:
        raise ExciteError(
            "approach",
            f"is for the ROS 2 formats (their first point's time); a {fmt} file's time starts at home, 0 s",
            approach,
            readers,
        )
    return FORMATS[fmt]
