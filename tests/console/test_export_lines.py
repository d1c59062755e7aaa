"""What export prints for the ROS 2 formats: the play command that waits for the controller, and
whether the trajectory carries effort."""

from dataclasses import replace
from pathlib import Path

import numpy as np

from excite_cli.console.export_lines import export_lines
from excite_cli.design.held_joints import HeldTorques
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


def test_a_standing_robot_s_largest_held_torque_is_said_against_its_effort_limit():
    tau = np.array([[10.0, -3.0], [20.0, 4.0], [5.0, 1.0]])
    held = HeldTorques(
        ("knee", "ankle"), np.zeros(2), tau, np.zeros((3, 1, 3)), np.zeros((1, 3)), np.array([100.0, 5.0]), 0
    )
    lines = export_lines(replace(EXPORT, held=held), 10.0, Path("m.csv"), "csv")
    said = "held joints (2): feed-forward that keeps the base and them still, feet flat; largest share ankle"
    assert f"{said} 4.0 Nm (80 % of its effort limit 5 Nm)" in lines
    position = export_lines(replace(EXPORT, held=held), 10.0, Path("g.yaml"), "ros2")
    assert any(line.startswith("held joints: not in the trajectory") for line in position)


def test_an_approach_shorter_than_needed_is_warned_with_the_time_and_the_reach():
    short = replace(EXPORT, approach=0.5, approach_needed=3.07, reach=(("j", 0.217),))
    lines = export_lines(short, 10.0, Path("run/bag"), "rosbag2")
    [warning] = [line for line in lines if line.startswith("warning: --approach 0.5 s")]
    assert "shorter than the 3.07 s" in warning and "starts within j 0.217 rad of it" in warning
    full = export_lines(replace(EXPORT, approach=3.07, approach_needed=3.07), 10.0, Path("run/bag"), "rosbag2")
    assert any("(from anywhere in its joint range" in line for line in full)
    assert not any(line.startswith("warning") for line in full)
