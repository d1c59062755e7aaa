"""The exported motion as a ROS 2 bag: read back with rosbags as ros2 bag play reads it, written
whole or not at all, replacing only a folder that holds a bag excite wrote and nothing else (never a
lab's recording, which ``ros2 bag record`` writes without excite's mark)."""

import numpy as np
import pytest
import yaml
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import Writer
from rosbags.typesys import Stores, get_typestore

from excite_cli.errors import CannotWrite, ExciteError, OutputExists
from excite_cli.identification.measured.bags import read_bag
from excite_cli.storage.rosbag import (
    CUSTOM_DATA_KEY,
    JOINT_STATES,
    MSGTYPE,
    START,
    TOPIC,
    check_bag_target,
    write_joint_states,
    write_rosbag,
)

JOINTS = ["shoulder", "elbow"]


#: Seven samples at 100 Hz: time [s], then q, q̇, q̈, τ (7, 2) told apart by their factors.
TIME = np.arange(7) / 100.0
Q = np.column_stack([np.sin(TIME), np.cos(TIME)])
MOTION = (Q, 2 * Q, 3 * Q, 4 * Q)


def _bag(folder, effort=False):
    return write_rosbag(folder, JOINTS, TIME, MOTION, effort=effort)


def _read(bag):
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        return [(c.topic, c.msgtype, reader.deserialize(raw, c.msgtype)) for c, _, raw in reader.messages()]


@pytest.mark.parametrize("effort", [False, True])
def test_the_bag_holds_one_joint_trajectory_with_every_sample(tmp_path, effort):
    [(topic, msgtype, message)] = _read(_bag(tmp_path / "bag", effort))
    assert (topic, msgtype) == (TOPIC, MSGTYPE)
    assert list(message.joint_names) == JOINTS
    assert (message.header.stamp.sec, message.header.stamp.nanosec) == (0, 0)  # start on arrival
    np.testing.assert_array_equal([p.positions for p in message.points], MOTION[0])
    np.testing.assert_array_equal([p.velocities for p in message.points], MOTION[1])
    np.testing.assert_array_equal([p.accelerations for p in message.points], MOTION[2])
    if effort:  # the feed-forward torque, asked for (an effort-controlled controller)
        np.testing.assert_array_equal([p.effort for p in message.points], MOTION[3])
    else:  # what every joint_trajectory_controller accepts
        assert all(len(p.effort) == 0 for p in message.points)
    assert [(p.time_from_start.sec, p.time_from_start.nanosec) for p in message.points][-1] == (0, 60_000_000)
    assert sorted(p.name for p in (tmp_path / "bag").iterdir()) == ["bag.db3", "metadata.yaml"]
    assert [p.name for p in tmp_path.iterdir()] == ["bag"]  # nothing left beside it


def test_force_replaces_a_bag_and_never_another_folder(tmp_path):
    bag = _bag(tmp_path / "bag")
    with pytest.raises(OutputExists):
        check_bag_target(bag, "output", force=False)
    check_bag_target(bag, "output", force=True)
    _bag(bag)
    assert len(_read(bag)) == 1
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "keep.txt").write_text("mine")
    with pytest.raises(ExciteError, match="is not only a ROS 2 bag .*; not replaced"):
        check_bag_target(tmp_path / "notes", "output", force=True)


@pytest.mark.parametrize("kind", ["dataset", "bag with notes", "bag metadata without its list"])
def test_force_never_replaces_a_folder_that_holds_more_than_a_bag(tmp_path, kind):
    """A dataset's own metadata.yaml (title, author, licence) beside its files, a bag a user added notes
    to, a metadata.yaml that does not list the bag's files: refused with force, nothing touched."""
    folder = tmp_path / "site"
    if kind == "dataset":
        folder.mkdir()
        (folder / "metadata.yaml").write_text("title: my data\nauthor: me\nlicence: CC-BY\n")
        (folder / "data.csv").write_text("t,q\n0,1\n")
    else:
        _bag(folder)
        if kind == "bag metadata without its list":
            text = (folder / "metadata.yaml").read_text().replace("relative_file_paths", "files")
            (folder / "metadata.yaml").write_text(text)
    if kind != "bag metadata without its list":
        (folder / "notes.txt").write_text("mine")
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    with pytest.raises(ExciteError, match="not only a ROS 2 bag") as error:
        check_bag_target(folder, "output", force=True)
    assert error.value.field == "output"
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before


def test_a_recorded_run_reads_back_through_identify_s_bag_reader(tmp_path):
    """What ``simulate`` writes with ``recording: rosbag2``: one JointState per sample on /joint_states,
    stamped from START; identify's reader gives back the samples and their times."""
    [bag] = write_joint_states([tmp_path / "run_1"], JOINTS, [(TIME, Q, MOTION[3])])
    table = read_bag(bag, JOINT_STATES, JOINTS[::-1])  # joints matched by name, in any order
    np.testing.assert_allclose(table.column("time", "time", bag) - START / 1e9, TIME, atol=1e-6)
    np.testing.assert_array_equal(table.column("position/elbow", "q", bag), Q[:, 1])
    np.testing.assert_array_equal(table.column("effort/shoulder", "tau", bag), MOTION[3][:, 0])
    assert "velocity/elbow" not in table.names  # left empty, as many drivers publish it


def test_a_full_disk_under_the_bag_writer_is_one_error_and_keeps_the_bag_it_would_replace(tmp_path, monkeypatch):
    """rosbags' SQLite storage raises sqlite3.OperationalError when the disk fills at close (issue 62: a
    108-line traceback): one CannotWrite, nothing of the new bag left, the earlier bag whole."""
    import sqlite3

    import excite_cli.storage.rosbag as rosbag

    bag = _bag(tmp_path / "bag")
    before = {p.name: p.read_bytes() for p in bag.iterdir()}

    class FullDisk(rosbag.Writer):
        def close(self):
            super().close()
            raise sqlite3.OperationalError("database or disk is full")

    monkeypatch.setattr(rosbag, "Writer", FullDisk)
    with pytest.raises(CannotWrite, match="disk is full"):
        check_bag_target(bag, "output", force=True)
        _bag(bag)
    with pytest.raises(CannotWrite):
        _bag(tmp_path / "new")
    assert {p.name: p.read_bytes() for p in bag.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]


def test_a_set_of_recorded_bags_replaces_the_earlier_set_whole_or_not_at_all(tmp_path, monkeypatch):
    """simulate --force over earlier bags (issue 62: a failure at run_2 lost run_1): when the disk fills
    at the second bag, both earlier bags stay as they were and nothing new is left."""
    import sqlite3

    import excite_cli.storage.rosbag as rosbag

    folders = [tmp_path / "bags" / f"run_{k}" for k in (1, 2)]
    write_joint_states(folders, JOINTS, [(TIME, Q, MOTION[3]), (TIME, 2 * Q, MOTION[3])])
    before = {f: {p.name: p.read_bytes() for p in f.iterdir()} for f in folders}
    opened = []

    class FullDiskAtTheSecond(rosbag.Writer):
        def close(self):
            super().close()
            opened.append(self)
            if len(opened) == 2:
                raise sqlite3.OperationalError("database or disk is full")

    monkeypatch.setattr(rosbag, "Writer", FullDiskAtTheSecond)
    with pytest.raises(CannotWrite, match="run_2.*disk is full"):
        write_joint_states(folders, JOINTS, [(TIME, 3 * Q, MOTION[3]), (TIME, 4 * Q, MOTION[3])])
    assert {f: {p.name: p.read_bytes() for p in f.iterdir()} for f in folders} == before
    assert sorted(p.name for p in (tmp_path / "bags").iterdir()) == ["run_1", "run_2"]


def _recording(folder):
    """A bag as ``ros2 bag record /joint_states`` writes it (no custom data of excite's): 3 messages."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    with Writer(folder, version=8) as writer:
        connection = writer.add_connection(JOINT_STATES, "sensor_msgs/msg/JointState", typestore=store)
        for k in range(3):
            header = types["std_msgs/msg/Header"](
                stamp=types["builtin_interfaces/msg/Time"](sec=k, nanosec=0), frame_id=""
            )
            message = types["sensor_msgs/msg/JointState"](
                header=header, name=JOINTS, position=np.zeros(2), velocity=np.zeros(0), effort=np.ones(2)
            )
            writer.write(connection, k * 10**9, store.serialize_cdr(message, "sensor_msgs/msg/JointState"))
    return folder


def test_a_lab_s_recording_is_never_replaced_and_excite_s_own_bags_carry_its_mark(tmp_path):
    recording = _recording(tmp_path / "fit")
    before = {p.name: p.read_bytes() for p in recording.iterdir()}
    for force in (False, True):
        with pytest.raises((OutputExists, ExciteError), match="fit"):
            check_bag_target(recording, "output", force)
    with pytest.raises(ExciteError, match="a ROS 2 bag excite did not write"):
        check_bag_target(recording, "output", True)
    assert {p.name: p.read_bytes() for p in recording.iterdir()} == before
    for ours in (_bag(tmp_path / "bag"), *write_joint_states([tmp_path / "run_1"], JOINTS, [(TIME, Q, Q)])):
        metadata = yaml.safe_load((ours / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
        assert metadata["custom_data"][CUSTOM_DATA_KEY].startswith("written by excite")
        check_bag_target(ours, "output", True)
    recorder = _recording(tmp_path / "recorder")  # a lab tool's mark that merely begins like excite's
    metadata = yaml.safe_load((recorder / "metadata.yaml").read_text())
    metadata["rosbag2_bagfile_information"]["custom_data"] = {CUSTOM_DATA_KEY: "written by excite_recorder 2.0"}
    (recorder / "metadata.yaml").write_text(yaml.safe_dump(metadata))
    with pytest.raises(ExciteError, match="a ROS 2 bag excite did not write"):
        check_bag_target(recorder, "output", True)
    (tmp_path / "link").symlink_to(recording)
    with pytest.raises(ExciteError, match="symbolic link"):
        check_bag_target(tmp_path / "link", "output", True)
