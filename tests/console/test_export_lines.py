"""What export prints for the ROS 2 formats: the play command that waits for the controller, and
whether the trajectory carries effort."""

from pathlib import Path

import numpy as np

from excite_cli.console.export_lines import export_lines
from excite_cli.storage.export import Export

T = np.arange(3) / 10.0
Q = np.zeros((3, 1))
EXPORT = Export(["j"], T, Q, Q, Q, Q, 10.0, 1, 1, [("trajectory", 0.0, 0.3)], -0.01, "none")


def test_a_bag_is_played_after_discovery_and_acknowledged():
    lines = export_lines(EXPORT, 10.0, Path("run/bag"), "rosbag2")
    [play] = [line for line in lines if line.startswith("play it:")]
    assert play.startswith("play it: ros2 bag play run/bag --delay 2 --wait-for-all-acked 5000")
    assert lines[-1].startswith("positions, velocities and accelerations: what every joint_trajectory_controller")


def test_effort_is_said_for_the_ros_formats_only():
    assert export_lines(EXPORT, 10.0, Path("g.yaml"), "ros2", effort=True)[-1].startswith("effort: the feed-forward")
    assert not any("effort" in line for line in export_lines(EXPORT, 10.0, Path("m.csv"), "csv"))
