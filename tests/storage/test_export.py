"""The played file: CSV, NPZ, a ROS 2 goal and a ROS 2 bag written from the same samples and read back."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from rosbags.typesys import Stores, get_typestore

from excite_cli.atomic import MARK
from excite_cli.config_file import load_problem, with_overrides
from excite_cli.design.held_joints import HeldTorques, held_joints
from excite_cli.design.resolve import build_excitation
from excite_cli.errors import ExciteError
from excite_cli.search.sequence import describe
from excite_cli.storage.export import Export, Played, export_trajectory
from excite_cli.storage.export_files import columns, write_export
from excite_cli.storage.formats import FORMATS, export_format
from excite_cli.storage.results import write_result
from excite_cli.storage.rosbag import MSGTYPE
from excite_cli.workflows.export import played_result

JOINTS = ["a", "b"]
CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def _at_rest_at_the_end(q: np.ndarray) -> np.ndarray:
    """Velocities 2q but zero at the last sample, as every exported motion ends (home, at rest)."""
    qd = 2 * q
    qd[-1] = 0.0
    return qd


@pytest.fixture
def export():
    t = np.arange(5) / 100.0
    q = np.column_stack([np.sin(t), np.cos(t)])
    qd = _at_rest_at_the_end(q)
    return Export(JOINTS, t, q, qd, 3 * q, 4 * q, 100.0, 2, 1, [("trajectory", 0.0, 0.05)], -0.01, "none")


def test_csv_and_npz_hold_the_same_samples_under_their_column_names(export, tmp_path):
    table = np.genfromtxt(write_export(tmp_path / "m.csv", export, "csv"), delimiter=",", names=True)
    assert (
        list(table.dtype.names)
        == columns(JOINTS)
        == [
            "time_s",
            "q_a_rad",
            "q_b_rad",
            "qd_a_rad_s",
            "qd_b_rad_s",
            "qdd_a_rad_s2",
            "qdd_b_rad_s2",
            "tau_a_Nm",
            "tau_b_Nm",
        ]
    )
    np.testing.assert_allclose(table["tau_b_Nm"], export.tau[:, 1], rtol=1e-9)
    archive = np.load(write_export(tmp_path / "m.npz", export, "npz"))
    np.testing.assert_array_equal(archive["qdd"], export.qdd)
    assert archive["joint_names"].tolist() == JOINTS


@pytest.mark.parametrize("effort", [False, True])
def test_a_ros2_goal_has_one_point_per_sample_with_its_time_and_builds_the_ros_message(export, tmp_path, effort):
    """The YAML goal's fields are trajectory_msgs/JointTrajectory(Point)'s as ROS 2 defines them
    (rosbags' Humble message store): they build such a message, which serializes to CDR. Effort only
    when asked."""
    goal = yaml.safe_load(write_export(tmp_path / "m.yaml", export, "ros2", effort).read_text())
    trajectory = goal["trajectory"]
    assert trajectory["joint_names"] == JOINTS and len(trajectory["points"]) == 5
    last = trajectory["points"][-1]
    assert last["time_from_start"] == {"sec": 0, "nanosec": 40_000_000}
    if effort:
        np.testing.assert_allclose(last["effort"], export.tau[-1])
    else:
        assert all("effort" not in point for point in trajectory["points"])
        for point in trajectory["points"]:
            point["effort"] = []
    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    points = [
        types["trajectory_msgs/msg/JointTrajectoryPoint"](
            **{k: np.asarray(v, dtype=float) for k, v in point.items() if k != "time_from_start"},
            time_from_start=types["builtin_interfaces/msg/Duration"](**point["time_from_start"]),
        )
        for point in trajectory["points"]
    ]
    header = types["std_msgs/msg/Header"](stamp=types["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id="")
    message = types[MSGTYPE](header=header, joint_names=trajectory["joint_names"], points=points)
    assert len(store.serialize_cdr(message, MSGTYPE)) > 0


def test_a_goal_longer_than_one_command_line_argument_is_refused_and_not_written(tmp_path):
    t = np.arange(5000) / 1000.0
    q = np.column_stack([np.sin(t), np.cos(t)])
    long = Export(JOINTS, t, q, _at_rest_at_the_end(q), q, q, 1000.0, 1, 1, [("trajectory", 0.0, 5.0)], -0.01, "none")
    with pytest.raises(ExciteError, match="more than the 128 KiB one command-line argument holds"):
        write_export(tmp_path / "m.yaml", long, "ros2")
    assert list(tmp_path.iterdir()) == []


def test_an_unknown_format_writes_nothing(export, tmp_path):
    with pytest.raises(ExciteError, match="format"):
        write_export(tmp_path / "m.xml", export, "xml")
    with pytest.raises(ExciteError, match="effort: is for the ROS 2 formats; a csv file holds τ always"):
        write_export(tmp_path / "m.csv", export, "csv", effort=True)
    assert list(tmp_path.iterdir()) == []


def test_an_approach_is_refused_for_a_data_file_whose_time_starts_at_home():
    for fmt in ("csv", "npz"):
        with pytest.raises(ExciteError, match=f"approach: is for the ROS 2 formats .*a {fmt} file's time starts"):
            export_format(fmt, approach=2.0)
    assert export_format("rosbag2", approach=2.0).controller and export_format("csv").name == "csv"


def test_a_trajectory_the_controller_would_refuse_is_not_written(export, tmp_path):
    """A motion that does not end at rest (which every export does) would be refused by the
    joint_trajectory_controller: excite says so and writes nothing, in both ROS 2 formats."""
    moving = replace(export, qd=2 * export.q)
    for fmt, name in (("ros2", "m.yaml"), ("rosbag2", "bag")):
        with pytest.raises(ExciteError, match="Velocity of last trajectory point of joint b is not zero"):
            write_export(tmp_path / name, moving, fmt)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_every_format_the_help_lists_is_written_with_its_ending(export, tmp_path, fmt):
    path = write_export(tmp_path / ("m" + FORMATS[fmt].suffix), export, fmt)
    written = path / "metadata.yaml" if fmt == "rosbag2" else path  # a bag is a folder
    assert written.is_file() and path.suffix == FORMATS[fmt].suffix
    assert written.stat().st_size > 0


def test_a_zmp_closer_to_the_edge_than_its_margin_is_a_warning_not_a_refusal(tmp_path):
    """The G1's ZMP is a prediction its stance decides (the constraint is advisory): a motion the
    optimizer's margin of 2 cm accepts, stored under a margin of 8.4 cm (standing still: 8.47 cm),
    exports with a warning."""
    problem = load_problem(CONFIGS / "g1_arms.yaml")
    alpha = build_excitation(problem).random_start(np.random.default_rng(2))
    strict = build_excitation(with_overrides(problem, {"constraints.zmp.margin": 0.084}))
    result = describe(strict, 1, alpha, np.zeros((0, strict.columns)))
    target = tmp_path / "g1.h5"
    write_result(target, strict, [result], 0, {"method": "optimized"})
    played = played_result(target, rate=100.0)
    margin = result.checks["zmp_min_margin_m"]
    assert 0.0 < margin < 0.084 and played.max_violation <= 0.0
    assert len(played.warnings) == 1 and "the robot may tip" in played.warnings[0]
    assert played.predictions[0].startswith("constraints.zmp: ZMP ")


def test_a_floating_base_without_soles_is_exported_with_a_word_on_what_its_torques_lack(tmp_path):
    """Issue 102: a G1 result whose config names no soles was exported without the held joints'
    feed-forward and without a word; the console and the CSV's notes now say so."""
    data = yaml.safe_load((CONFIGS / "g1_arms.yaml").read_text())
    del data["constraints"]["zmp"], data["constraints"]["com"]
    (tmp_path / "g1.yaml").write_text(yaml.safe_dump(data))
    problem = load_problem(tmp_path / "g1.yaml")
    excitation = build_excitation(problem)
    result = describe(
        excitation, 1, excitation.random_start(np.random.default_rng(0)), np.zeros((0, excitation.columns))
    )
    target = tmp_path / "g1.h5"
    write_result(target, excitation, [result], 0, {"method": "optimized"})
    played = played_result(target, rate=50.0)
    assert played.held is None
    said = [w for w in played.warnings if w.startswith("constraints.zmp.support_links: the robot has a floating base")]
    assert len(said) == 1 and "names no soles" in said[0]
    notes = [line for line in write_export(tmp_path / "g1.csv", played, "csv").read_text().splitlines() if "#" in line]
    assert f"# warning: {said[0]}" in notes and notes[-1] == f"# {MARK} export"


@pytest.fixture
def standing(export):
    """The fixture's motion with two held joints, held at 0.1 and −0.2 rad."""
    tau = np.column_stack([np.linspace(1.0, 2.0, 5), np.linspace(-3.0, -1.0, 5)])
    forces, points = np.zeros((5, 4, 3)), np.zeros((4, 3))
    held = HeldTorques(("knee", "hip"), np.array([0.1, -0.2]), tau, forces, points, np.array([50.0, 0.0]), 0)
    return replace(export, held=held)


def test_a_standing_robot_s_held_joints_are_columns_and_arrays_beside_the_active_joints(standing, tmp_path):
    path = write_export(tmp_path / "m.csv", standing, "csv")
    header = [line for line in path.read_text().splitlines() if line.startswith("#")]
    assert header[-2].endswith("knee at 0.1 rad, hip at -0.2 rad") and header[-1] == f"# {MARK} export"
    table = np.genfromtxt(path, delimiter=",", names=True)
    assert list(table.dtype.names) == columns(JOINTS) + ["tau_knee_Nm", "tau_hip_Nm"]
    np.testing.assert_allclose(table["tau_hip_Nm"], standing.held.tau[:, 1], rtol=1e-9)
    archive = np.load(write_export(tmp_path / "m.npz", standing, "npz"))
    assert archive["held_joint_names"].tolist() == ["knee", "hip"]
    np.testing.assert_array_equal(archive["tau_held"], standing.held.tau)
    np.testing.assert_array_equal(archive["held_positions"], [0.1, -0.2])


def test_a_standing_export_reads_with_numpy_and_pandas_and_says_what_each_torque_is(standing, tmp_path):
    """The column names are the first line (numpy's ``names=True`` takes the first line, commented or
    not); the notes after the rows say what the active and held torques are, the ground force's split
    and the held joints' peak against its limit (knee: 2 Nm of 50 Nm; hip has none)."""
    import pandas

    path = write_export(tmp_path / "m.csv", standing, "csv")
    table = np.genfromtxt(path, delimiter=",", names=True)
    frame = pandas.read_csv(path, comment="#")
    assert list(table.dtype.names) == list(frame.columns) == columns(JOINTS) + ["tau_knee_Nm", "tau_hip_Nm"]
    np.testing.assert_allclose(frame["tau_knee_Nm"], standing.held.tau[:, 0], rtol=1e-9)
    assert len(frame) == table.size == standing.time.size
    notes = [line for line in path.read_text().splitlines() if line.startswith("#")]
    assert any("tau of the active joints (2 columns after qdd): inverse dynamics (RNEA)" in n for n in notes)
    [rule] = [n for n in notes if n.startswith("# tau of the held joints (2 columns")]
    assert "least-norm forces" in rule and "friction cone" in rule
    assert "# held joints' peak: knee 2 Nm, 4 % of its URDF limit 50 Nm" in notes


def test_held_joints_reach_an_effort_controller_s_trajectory_and_stay_out_of_a_position_controller_s(
    standing, tmp_path
):
    """With effort, one trajectory over the whole body: the held joints at their values, at rest, their
    feed-forward as effort, which the controller's rules accept; without, the active joints only (a
    controller refuses a joint it does not command)."""
    points = yaml.safe_load(write_export(tmp_path / "e.yaml", standing, "ros2", True).read_text())["trajectory"]
    assert points["joint_names"] == JOINTS + ["knee", "hip"]
    last = points["points"][-1]
    np.testing.assert_allclose(last["positions"][2:], [0.1, -0.2])
    np.testing.assert_allclose(last["velocities"][2:] + last["accelerations"][2:], 0.0)
    np.testing.assert_allclose(last["effort"], np.r_[standing.tau[-1], standing.held.tau[-1]])
    plain = yaml.safe_load(write_export(tmp_path / "p.yaml", standing, "ros2").read_text())["trajectory"]
    assert plain["joint_names"] == JOINTS


def test_a_held_joint_s_feed_forward_above_its_effort_limit_is_refused(tmp_path):
    problem = load_problem(CONFIGS / "g1_arms.yaml")
    excitation = build_excitation(problem)
    held = held_joints(problem.robot, problem.folder, problem.constraints, excitation.robot)
    alpha = excitation.random_start(np.random.default_rng(2))
    how = Played(tmp_path / "g1.h5", 1, 50.0, 1, 1.0)
    assert export_trajectory(excitation, alpha, how, held).held.peak()[1] < 1.0
    held.effort = held.effort / 20.0
    with pytest.raises(ExciteError, match="of the held joint 'waist_pitch_joint' to keep the robot still, above its"):
        export_trajectory(excitation, alpha, how, held)
