"""ROS bags identify with no conversion: bags written here with rosbags' own writers (ROS 2 SQLite3
and MCAP, ROS 1) from a simulated run read back to the same samples as its CSV, joints matched by
name whatever their order in the messages, and a bag identifies the simulated friction."""

from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import CONFIGS, write_config
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Ros2Writer
from rosbags.typesys import Stores, get_typestore
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.errors import ExciteError, ExciteWarning
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.measured.bags import is_bag, read_bag
from excite_cli.identification.measured.measurements import load_run
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.workflows.simulate import simulate_runs

JOINTS = [f"panda_joint{k}" for k in range(1, 8)]
MSGTYPE = "sensor_msgs/msg/JointState"
T0 = 1_700_000_000  # Unix time [s] of the first sample


def _messages(table: np.ndarray, store: Stores, seq: bool):
    """(timestamp [ns], message) per row, joints in reversed order, and a gripper's message between."""
    types = get_typestore(store).types
    Time, Header, JointState = (types[t] for t in ("builtin_interfaces/msg/Time", "std_msgs/msg/Header", MSGTYPE))
    order = list(range(7))[::-1]
    for k, row in enumerate(table):
        ns = T0 * 10**9 + int(round(row[0] * 1e9))
        header = Header(**({"seq": k} if seq else {}), stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id="")
        q, tau = row[1:8], row[8:15]
        yield (
            ns,
            JointState(
                header=header,
                name=[JOINTS[j] for j in order],
                position=q[order],
                velocity=np.zeros(0),
                effort=tau[order],
            ),
        )
        if k % 50 == 0:  # another publisher on the same topic
            yield (
                ns,
                JointState(
                    header=header,
                    name=["panda_finger_joint1"],
                    position=np.zeros(1),
                    velocity=np.zeros(1),
                    effort=np.zeros(1),
                ),
            )


def write_bag(path: Path, table: np.ndarray, kind: str) -> Path:
    """A bag of ``table`` (time, q (7), τ (7)) on /joint_states: ``ros2`` (SQLite3), ``mcap`` or ``ros1``."""
    if kind == "ros1":
        store = get_typestore(Stores.ROS1_NOETIC)
        with Ros1Writer(path) as writer:
            connection = writer.add_connection("/joint_states", MSGTYPE, typestore=store)
            for ns, message in _messages(table, Stores.ROS1_NOETIC, seq=True):
                writer.write(connection, ns, store.serialize_ros1(message, MSGTYPE))
        return path
    store = get_typestore(Stores.ROS2_HUMBLE)
    plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
    with Ros2Writer(path, version=9, storage_plugin=plugin) as writer:
        connection = writer.add_connection("/joint_states", MSGTYPE, typestore=store)
        for ns, message in _messages(table, Stores.ROS2_HUMBLE, seq=False):
            writer.write(connection, ns, store.serialize_cdr(message, MSGTYPE))
    return path


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """One simulated Panda run with Coulomb friction 0.4 Nm on every joint (CSV), from the smoke problem."""
    tmp = tmp_path_factory.mktemp("bags")
    data = yaml.safe_load((CONFIGS / "smoke.yaml").read_text())
    data.update(sequence={"iterations": 1}, output=str(tmp / "panda.h5"))
    result = CliRunner().invoke(app, ["optimize", str(write_config(tmp, data))])
    assert result.exit_code == 0, result.output
    sim = SimulationConfig(sample_rate=250, periods=8, torque_noise=0.05, seed=3, effects={"coulomb": {"*": 0.4}})
    simulate_runs(tmp / "panda.h5", sim, tmp)
    return tmp, np.loadtxt(tmp / "run_1.csv", delimiter=",", skiprows=1)


def _config(tmp: Path, run: str, extra: dict | None = None) -> IdentifyProblem:
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {"runs": [{"file": run, "role": "blocks"}], **(extra or {})},
        "identification": {"candidates": ["coulomb"]},
        "output": str(tmp / "ident.h5"),
    }
    return load_problem(write_config(tmp, config, "identify.yaml"), IdentifyProblem)


@pytest.mark.parametrize("kind, name", [("ros2", "sqlite_bag"), ("mcap", "mcap_bag"), ("ros1", "run.bag")])
def test_a_bag_reads_to_the_samples_of_its_csv(simulated, kind, name):
    tmp, table = simulated
    write_bag(tmp / name, table, kind)
    problem = _config(tmp, name)
    run = load_run(problem.data.runs[0], problem.data, problem.robot.active_joints, problem.folder)
    assert is_bag(tmp / name) and not is_bag(tmp / "run_1.csv")
    raw = read_bag(tmp / name, "/joint_states", JOINTS[::-1])  # matched by name, in any order
    np.testing.assert_allclose(raw.column(f"position/{JOINTS[-1]}", "q", tmp / name), table[:, 7], rtol=0, atol=1e-12)
    np.testing.assert_allclose(run.time - T0, table[:, 0], atol=2e-6)
    np.testing.assert_allclose(run.q, table[:, 1:8], rtol=0, atol=1e-12)
    np.testing.assert_allclose(run.tau, table[:, 8:15], rtol=0, atol=1e-12)
    assert run.qd is None  # the messages leave velocity empty


@pytest.mark.end_to_end
def test_a_bag_identifies_the_simulated_friction(simulated):
    tmp, table = simulated
    bag = write_bag(tmp / "identify_bag", table, "mcap")
    report = run_identification(_config(tmp, next(bag.glob("*.mcap")).relative_to(tmp).as_posix()))[0]
    found = {report.joints[t.joint]: v for t, _, v, _ in report.effect_values() if t.effect == "coulomb"}
    assert set(found) == set(JOINTS) and all(abs(v - 0.4) < 0.06 for v in found.values())


def test_a_bag_without_the_topic_or_a_file_without_columns_is_named(simulated):
    tmp, table = simulated
    write_bag(tmp / "topic.bag", table[:50], "ros1")
    problem = _config(tmp, "topic.bag", {"topic": "/robot/joint_states"})
    with pytest.raises(ExciteError) as caught:
        load_run(problem.data.runs[0], problem.data, problem.robot.active_joints, problem.folder)
    assert caught.value.field == "data.topic" and "/joint_states" in caught.value.problem
    problem = _config(tmp, "run_1.csv")
    with pytest.raises(ExciteError) as caught:
        load_run(problem.data.runs[0], problem.data, problem.robot.active_joints, problem.folder)
    assert caught.value.field == "data.columns"


def test_messages_with_only_some_of_the_joints_are_counted_and_named(simulated, tmp_path):
    """Issue 62: a bag where every other message lacks a joint lost them without a count (then its run
    was refused for a rate half the recording's). A gripper's messages (none of the joints) are passed
    over without a word, as in the other bags here."""
    _, table = simulated
    store = get_typestore(Stores.ROS2_HUMBLE)
    path = tmp_path / "partial"
    with Ros2Writer(path, version=9) as writer:
        connection = writer.add_connection("/joint_states", MSGTYPE, typestore=store)
        for k, (ns, message) in enumerate(_messages(table[:200], Stores.ROS2_HUMBLE, seq=False)):
            if k % 2 and len(message.name) == 7:  # every other arm message loses its first joint
                message.name, message.position, message.effort = (
                    x[1:] for x in (message.name, message.position, message.effort)
                )
            writer.write(connection, ns, store.serialize_cdr(message, MSGTYPE))
    with pytest.warns(ExciteWarning, match=r"partial: 100 of 200 messages on /joint_states carry only some"):
        read = read_bag(path, "/joint_states", JOINTS)
    assert read.dropped == 100 and read.values.shape[0] == 100


def test_a_driver_that_publishes_the_arm_in_two_messages_reads_as_one(simulated, tmp_path):
    """Each sample as two JointState messages, joints 1-4 and 5-7 (the second stamped 0.3 ms later, in
    reversed order some of the time): the same samples as the whole messages, nothing dropped."""
    _, table = simulated
    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    Time, Header, JointState = (types[t] for t in ("builtin_interfaces/msg/Time", "std_msgs/msg/Header", MSGTYPE))
    path = tmp_path / "split"
    with Ros2Writer(path, version=9) as writer:
        connection = writer.add_connection("/joint_states", MSGTYPE, typestore=store)
        for k, row in enumerate(table[:300]):
            ns = T0 * 10**9 + int(round(row[0] * 1e9))
            parts = [(range(0, 4), ns), (range(4, 7), ns + 300_000)]
            for part, stamp in parts[::-1] if k % 3 == 0 else parts:
                header = Header(stamp=Time(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id="")
                message = JointState(
                    header=header,
                    name=[JOINTS[j] for j in part],
                    position=row[1:8][list(part)],
                    velocity=np.zeros(0),
                    effort=row[8:15][list(part)],
                )
                writer.write(connection, stamp, store.serialize_cdr(message, MSGTYPE))
    whole = read_bag(write_bag(tmp_path / "whole", table[:300], "ros2"), "/joint_states", JOINTS)
    read = read_bag(path, "/joint_states", JOINTS)
    assert read.dropped == 0 and read.names == whole.names
    np.testing.assert_allclose(read.values[:, 1:], whole.values[:, 1:], rtol=0, atol=0)
    np.testing.assert_allclose(read.values[:, 0], whole.values[:, 0], atol=4e-4)
