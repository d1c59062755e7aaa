"""The exported trajectory against the joint_trajectory_controller's own acceptance rules (written from
ros2_controllers' validate_trajectory_msg, see the module): the bag and the goal excite writes pass
them for a position-controlled arm and, with effort, for an effort-controlled one; each rule refuses
what the controller refuses. The bag's format is pinned to what Humble's rosbag2 reads."""

import numpy as np
import pytest
import yaml
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from excite_cli.storage.export import Export
from excite_cli.storage.export_files import write_export
from excite_cli.storage.trajectory_controller import controller_refusals

JOINTS = ["shoulder", "elbow", "wrist"]


@pytest.fixture
def played():
    """A motion as export plays it: home → excursion → home, at rest at both ends (quintic)."""
    t = np.linspace(0.0, 2.0, 201)
    s = t / 2.0
    blend = 10 * s**3 - 15 * s**4 + 6 * s**5  # 0 → 1 at rest
    bump = np.sin(np.pi * blend)[:, None] * np.array([0.3, -0.2, 0.5])
    qd = np.gradient(bump, t, axis=0)
    qd[[0, -1]] = 0.0
    qdd = np.gradient(qd, t, axis=0)
    return Export(JOINTS, t, bump, qd, qdd, 5 * bump, 100.0, 1, 1, [("trajectory", 0.0, 2.0)], -0.01, "none")


def _from_bag(folder):
    with AnyReader([folder], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        [(connection, _, raw)] = list(reader.messages())
        message = reader.deserialize(raw, connection.msgtype)
    points = message.points
    time_ns = np.array([p.time_from_start.sec * 10**9 + p.time_from_start.nanosec for p in points])
    fields = [np.array([getattr(p, name) for p in points]) for name in ("positions", "velocities", "accelerations")]
    effort = np.array([p.effort for p in points])
    return list(message.joint_names), time_ns, fields, (effort if effort.size else None)


@pytest.mark.parametrize("effort", [False, True])
def test_the_written_bag_passes_the_controller_s_rules(played, tmp_path, effort):
    """Read back with rosbags (independent of excite's writer): no effort by default, which every
    command interface accepts; with effort, accepted by an effort-controlled controller only."""
    names, time_ns, (q, qd, qdd), tau = _from_bag(write_export(tmp_path / "bag", played, "rosbag2", effort))
    assert (tau is not None) == effort
    assert controller_refusals(names, time_ns, q, qd, qdd, tau, effort_interface=effort) == []
    if effort:
        assert controller_refusals(names, time_ns, q, qd, qdd, tau, effort_interface=False) == [
            "Trajectories with effort fields are currently not supported."
        ]


def test_the_written_goal_passes_the_controller_s_rules(played, tmp_path):
    points = yaml.safe_load(write_export(tmp_path / "goal.yaml", played, "ros2").read_text())["trajectory"]["points"]
    time_ns = np.array([p["time_from_start"]["sec"] * 10**9 + p["time_from_start"]["nanosec"] for p in points])
    fields = [np.array([p[name] for p in points]) for name in ("positions", "velocities", "accelerations")]
    assert all("effort" not in p for p in points)
    assert controller_refusals(JOINTS, time_ns, *fields, None) == []


def test_the_bag_is_rosbag2_format_8_in_sqlite3_which_humble_reads(played, tmp_path):
    """rosbags' newest format (9) is refused by Humble's rosbag2 ("bad conversion")."""
    info = yaml.safe_load((write_export(tmp_path / "bag", played, "rosbag2") / "metadata.yaml").read_text())
    info = info["rosbag2_bagfile_information"]
    assert info["version"] == 8 and info["storage_identifier"] == "sqlite3"
    [topic] = info["topics_with_message_count"]
    assert topic["topic_metadata"]["type"] == "trajectory_msgs/msg/JointTrajectory" and topic["message_count"] == 1


def test_each_rule_refuses_what_the_controller_refuses(played):
    t = np.round(played.time * 1e9).astype(np.int64)
    q, qd, qdd = played.q, played.qd, played.qdd
    assert controller_refusals(JOINTS, t, q, qd, qdd, None) == []
    repeated = t.copy()
    repeated[5] = repeated[4]
    moving = qd.copy()
    moving[-1, 1] = 1e-3
    cases = {
        "Time between points 4 and 5 is not strictly increasing": (JOINTS, repeated, q, qd, qdd),
        "Velocity of last trajectory point of joint elbow is not zero": (JOINTS, t, q, moving, qdd),
        "Mismatch between joint_names size (3) and velocities (201, 2)": (JOINTS, t, q, qd[:, :2], qdd),
        "Empty joint names on incoming trajectory.": ([], t, q[:, :0], None, None),
        "a joint name is given twice": (["a", "a", "b"], t, q, qd, qdd),
        "Empty trajectory received.": (JOINTS, t[:0], q[:0], None, None),
        "positions holds NaN or infinite values": (JOINTS, t, np.where(q > 0.2, np.nan, q), qd, qdd),
    }
    for reason, arguments in cases.items():
        assert reason in controller_refusals(*arguments, None), reason
    assert controller_refusals(JOINTS, t, q, qd, None, None) == []  # accelerations may be empty
