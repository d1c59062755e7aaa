"""The export's file formats, without what writes them (the command line's help lists them at
start-up; :mod:`~excite_cli.storage.export` writes them)."""

from excite_cli.errors import ExciteError

#: File formats and their file-name endings (``ros2``: a FollowJointTrajectory goal as YAML;
#: ``rosbag2``: a ROS 2 bag, a folder without an ending).
FORMATS = {"csv": "csv", "npz": "npz", "ros2": "yaml", "rosbag2": ""}
#: The formats a ROS 2 joint_trajectory_controller reads (the others are data files).
ROS_FORMATS = ("ros2", "rosbag2")


def check_format(fmt: str, effort: bool = False) -> None:
    """That ``fmt`` is one of :data:`FORMATS`, and ``effort`` (τ as a trajectory's effort) asked only of
    a ROS 2 format (a data file holds τ always).

    Raises:
        ExciteError: another format, or effort for a data file.
    """
    if fmt not in FORMATS:
        raise ExciteError("format", f"must be one of {', '.join(FORMATS)} (got {fmt!r})")
    if effort and fmt not in ROS_FORMATS:
        raise ExciteError(
            "effort", f"is for the ROS 2 formats; a {fmt} file holds τ always", expected="ros2 or rosbag2"
        )
