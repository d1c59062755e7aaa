"""The exported motion as a ROS 2 bag: read back with rosbags as ros2 bag play reads it, written
whole or not at all, replacing only a bag."""

import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from excite_cli.errors import ExciteError, OutputExists
from excite_cli.storage.export import Export
from excite_cli.storage.rosbag import MSGTYPE, TOPIC, check_bag_target, write_rosbag

JOINTS = ["shoulder", "elbow"]


@pytest.fixture
def export():
    t = np.arange(7) / 100.0
    q = np.column_stack([np.sin(t), np.cos(t)])
    return Export(JOINTS, t, q, 2 * q, 3 * q, 4 * q, 100.0, 3, 1, [("trajectory", 0.0, 0.06)], -0.01, "none")


def _bag(folder, e):
    return write_rosbag(folder, e.joint_names, e.time, (e.q, e.qd, e.qdd, e.tau))


def _read(bag):
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        return [(c.topic, c.msgtype, reader.deserialize(raw, c.msgtype)) for c, _, raw in reader.messages()]


def test_the_bag_holds_one_joint_trajectory_with_every_sample(export, tmp_path):
    [(topic, msgtype, message)] = _read(_bag(tmp_path / "bag", export))
    assert (topic, msgtype) == (TOPIC, MSGTYPE)
    assert list(message.joint_names) == JOINTS
    assert (message.header.stamp.sec, message.header.stamp.nanosec) == (0, 0)  # start on arrival
    np.testing.assert_array_equal([p.positions for p in message.points], export.q)
    np.testing.assert_array_equal([p.velocities for p in message.points], export.qd)
    np.testing.assert_array_equal([p.accelerations for p in message.points], export.qdd)
    np.testing.assert_array_equal([p.effort for p in message.points], export.tau)
    assert [(p.time_from_start.sec, p.time_from_start.nanosec) for p in message.points][-1] == (0, 60_000_000)
    assert sorted(p.name for p in (tmp_path / "bag").iterdir()) == ["bag.db3", "metadata.yaml"]
    assert [p.name for p in tmp_path.iterdir()] == ["bag"]  # nothing left beside it


def test_force_replaces_a_bag_and_never_another_folder(export, tmp_path):
    bag = _bag(tmp_path / "bag", export)
    with pytest.raises(OutputExists):
        check_bag_target(bag, "output", force=False)
    check_bag_target(bag, "output", force=True)
    _bag(bag, export)
    assert len(_read(bag)) == 1
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "keep.txt").write_text("mine")
    with pytest.raises(ExciteError, match="is not a ROS 2 bag folder; not replaced"):
        check_bag_target(tmp_path / "notes", "output", force=True)
