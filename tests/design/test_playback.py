"""From an optimized trajectory to a robot: rest at both ends on the Panda, quintic transitions, the
exported file at 1 kHz against pinocchio's RNEA and the URDF's limits, the posture strip."""

import re

import h5py
import numpy as np
import pinocchio as pin
import pytest
from conftest import CONFIGS
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import result_problem
from excite_cli.constraints import JointLimits
from excite_cli.constraints.lse import GRID_MARGIN
from excite_cli.design.playback import RESOLUTION, Transition, approach_duration, approach_reach, plan_transition
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.robot_files import example_robot_data_root
from excite_cli.errors import ExciteError
from excite_cli.storage.export import Played, export_trajectory
from excite_cli.storage.results import read_alphas
from excite_cli.storage.rosbag import TOPIC
from excite_cli.workflows.export import played_result

runner = CliRunner()
PANDA_URDF = "example-robot-data/robots/panda_description/urdf/panda.urdf"


def _fourier_rates(alpha, omega, t):
    """q̇, q̈ (n,) of Eq. 50 at time t, written out independently of the library."""
    N = (alpha.shape[1] - 1) // 2
    k = np.arange(1, N + 1) * omega
    a, b = alpha[:, 1 : N + 1], alpha[:, N + 1 :]
    qd = (a * k * np.cos(k * t) - b * k * np.sin(k * t)).sum(axis=1)
    qdd = (-a * k**2 * np.sin(k * t) - b * k**2 * np.cos(k * t)).sum(axis=1)
    return qd, qdd


@pytest.fixture(scope="module")
def panda_runs(tmp_path_factory):
    """`excite optimize configs/panda_joint_limits.yaml` (boundary rest) and with boundary periodic, both screening
    4 starts instead of the shipped 16, continuing them to 60 solver iterations instead of 200, over 2 iterations
    instead of 3 (the test's time: what is tested is the motion's ends and constraints, not its optimality)."""
    tmp = tmp_path_factory.mktemp("panda")
    shipped = (CONFIGS / "panda_joint_limits.yaml").read_text()
    assert "starts: 16" in shipped and "max_iterations: 200" in shipped
    shipped = shipped.replace("max_iterations: 200", "max_iterations: 60")
    shipped = shipped.replace("iterations: 3", "iterations: 2")
    configs = {"rest": tmp / "rest.yaml", "periodic": tmp / "periodic.yaml"}
    configs["rest"].write_text(shipped.replace("starts: 16", "starts: 4"))
    configs["periodic"].write_text(configs["rest"].read_text().replace("boundary: rest", "boundary: periodic"))
    runs = {}
    for name, config in configs.items():
        out = tmp / f"{name}.h5"
        run = runner.invoke(app, ["optimize", str(config), "-o", str(out)])
        assert run.exit_code == 0, run.output
        runs[name] = out
    return runs


def test_rest_run_starts_and_ends_at_rest_and_keeps_every_constraint(panda_runs):
    with h5py.File(panda_runs["rest"]) as f:
        assert "boundary: rest" in f.attrs["config"]
        for k in f["iterations"]:
            it = f["iterations"][k]
            alpha, T = it["alpha"][()], it["time"][-1]
            for t in (0.0, T):
                qd, qdd = _fourier_rates(alpha, 2 * np.pi / 10.0, t)
                assert np.abs(qd).max() <= 1e-9 and np.abs(qdd).max() <= 1e-9
            assert it.attrs["max_violation"] <= 0.0
            assert it.attrs["transition_max_violation"] <= 0.0 and it.attrs["transition_in_s"] > 0.0


def test_rest_keeps_excitation_within_25_percent_of_periodic(panda_runs):
    conds = {}
    for name, path in panda_runs.items():
        with h5py.File(path) as f:
            conds[name] = f["table"]["cond_stacked"][-1]
    assert conds["rest"] <= 1.25 * conds["periodic"], conds


def test_posture_strip_and_plots_are_written(panda_runs):
    for suffix in ("postures", "trajectories", "cond"):
        assert panda_runs["rest"].with_name(f"rest_{suffix}.png").stat().st_size > 10_000


def test_export_at_1khz_plays_from_home_to_home_with_rnea_torques(panda_runs, tmp_path):
    target = tmp_path / "panda_1khz.csv"
    run = runner.invoke(app, ["export", str(panda_runs["rest"]), "--rate", "1000", "--periods", "2", "-o", str(target)])
    assert run.exit_code == 0, run.output
    body = [line for line in target.read_text().splitlines() if not line.startswith("#")]
    header, table = body[0].split(","), np.loadtxt(body[1:], delimiter=",")
    n = 7
    time, q, qd, qdd, tau = table[:, 0], *np.split(table[:, 1:], 4, axis=1)
    assert header[1] == "q_panda_joint1_rad" and header[-1] == "tau_panda_joint7_Nm"
    assert np.allclose(np.diff(time), 1e-3, atol=1e-9)
    # rest at the home posture at both ends; home is 0 rad where 0 is inside the limits (joints 1-5, 7)
    for row in (0, -1):
        assert np.abs(qd[row]).max() < 1e-9 and np.abs(qdd[row]).max() < 1e-9
        assert np.abs(q[row][[0, 1, 2, 4, 6]]).max() < 1e-9
    assert np.allclose(q[0], q[-1], atol=1e-9)
    # the limits of configs/panda_joint_limits.yaml from the URDF, checked on every exported sample
    full = pin.buildModelFromUrdf(str(example_robot_data_root() / PANDA_URDF))
    lower, upper = full.lowerPositionLimit[:n] + 0.1, full.upperPositionLimit[:n] - 0.1
    assert np.all(q >= lower - 1e-9) and np.all(q <= upper + 1e-9)
    assert np.abs(qd).max() <= 1.5 and np.abs(qdd).max() <= 5.0
    # feed-forward torques against pinocchio's RNEA of the full URDF (fingers at 0) at random rows; the CSV
    # holds 10 significant digits, so RNEA of its rounded q, q̇, q̈ (q̈ up to 5 rad/s², rounded to ~5e-10)
    # differs from the written torque by up to ~1e-8 N·m: compared to 1e-7 N·m
    data = full.createData()
    for row in np.random.default_rng(0).choice(len(time), 25, replace=False):
        expected = pin.rnea(full, data, np.r_[q[row], 0.0, 0.0], np.r_[qd[row], 0.0, 0.0], np.r_[qdd[row], 0.0, 0.0])[
            :n
        ]
        assert np.allclose(tau[row], expected, rtol=1e-8, atol=1e-7)
    assert "every constraint holds" in run.output


def test_export_at_half_speed_plays_the_same_path_in_twice_the_time(panda_runs):
    """q_s(t) = q(t/2): the slow file's sample 2k is the fast one's k, with q̇ halved, q̈ quartered and the
    torques RNEA's of those."""
    fast = played_result(panda_runs["rest"], rate=200.0)
    slow = played_result(panda_runs["rest"], rate=200.0, speed=0.5)
    count = min(len(fast.time), (len(slow.time) + 1) // 2)
    np.testing.assert_allclose(slow.time[: 2 * count : 2], 2 * fast.time[:count], atol=1e-12)
    np.testing.assert_allclose(slow.q[: 2 * count : 2], fast.q[:count], atol=1e-12)
    np.testing.assert_allclose(slow.qd[: 2 * count : 2], 0.5 * fast.qd[:count], atol=1e-12)
    np.testing.assert_allclose(slow.qdd[: 2 * count : 2], 0.25 * fast.qdd[:count], atol=1e-12)
    assert slow.speed == 0.5 and slow.segments[-1][1] == pytest.approx(2 * fast.segments[-1][1])
    full = pin.buildModelFromUrdf(str(example_robot_data_root() / PANDA_URDF))
    data, k = full.createData(), len(slow.time) // 3
    expected = pin.rnea(full, data, *(np.r_[x[k], 0.0, 0.0] for x in (slow.q, slow.qd, slow.qdd)))[:7]
    np.testing.assert_allclose(slow.tau[k], expected, rtol=1e-8, atol=1e-8)
    assert slow.predictions == () and slow.warnings == ()  # a fixed-base arm: nothing to tip


def test_export_npz_has_the_same_samples(panda_runs, tmp_path):
    run = runner.invoke(
        app,
        [
            "export",
            str(panda_runs["rest"]),
            "-k",
            "1",
            "--rate",
            "200",
            "--format",
            "npz",
            "-o",
            str(tmp_path / "a.npz"),
        ],
    )
    assert run.exit_code == 0, run.output
    data = np.load(tmp_path / "a.npz")
    assert list(data["joint_names"])[0] == "panda_joint1" and data["q"].shape == data["tau"].shape
    assert np.allclose(np.diff(data["time"]), 5e-3)


def test_a_ros2_goal_longer_than_one_command_line_argument_is_refused_naming_the_bag(panda_runs):
    """A 7-joint goal at 50 Hz is about 400 kB: ``send_goal … "$(cat FILE)"`` fails beyond 128 KiB."""
    argv = ["export", str(panda_runs["rest"]), "-k", "1", "--rate", "50", "--format", "ros2"]
    result = runner.invoke(app, argv, env={"COLUMNS": "400"})
    assert result.exit_code == 2
    assert "more than the 128 KiB one command-line argument holds" in result.output and "rosbag2" in result.output
    assert not panda_runs["rest"].with_name(panda_runs["rest"].stem + "_iteration1_50Hz.yaml").exists()


def test_a_rosbag2_export_plays_the_samples_of_the_csv(panda_runs, tmp_path):
    """Read back with rosbags as ``ros2 bag play`` would: one JointTrajectory on the controller's topic
    whose points are the CSV's rows (positions, time_from_start; with ``--effort``, effort = the
    feed-forward torque, else no effort), and the printed play command waits for the controller."""
    argv = ["export", str(panda_runs["rest"]), "-k", "1", "--rate", "50"]
    assert runner.invoke(app, [*argv, "-o", str(tmp_path / "play.csv")]).exit_code == 0
    plain = runner.invoke(app, [*argv, "--format", "rosbag2", "-o", str(tmp_path / "plain")], env={"COLUMNS": "400"})
    assert plain.exit_code == 0, plain.output
    assert f"ros2 bag play {tmp_path / 'plain'} --delay 2 --wait-for-all-acked 5000" in plain.output
    assert "positions, velocities and accelerations: what every joint_trajectory_controller accepts" in plain.output
    with AnyReader([tmp_path / "plain"], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        [plain_message] = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()]
    assert all(len(p.effort) == 0 for p in plain_message.points)  # no effort unless asked
    argv += ["--effort"]
    result = runner.invoke(app, [*argv, "--format", "rosbag2", "-o", str(tmp_path / "bag")], env={"COLUMNS": "400"})
    assert result.exit_code == 0, result.output
    assert f"ros2 bag play {tmp_path / 'bag'}" in result.output and "effort-controlled" in result.output
    time, q, _, _, tau = _csv(tmp_path / "play.csv")
    with AnyReader([tmp_path / "bag"], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        assert [(c.topic, c.msgtype) for c in reader.connections] == [(TOPIC, "trajectory_msgs/msg/JointTrajectory")]
        messages = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()]
    assert len(messages) == 1
    message = messages[0]
    assert list(message.joint_names) == [f"panda_joint{k}" for k in range(1, 8)]
    np.testing.assert_allclose([p.positions for p in message.points], q, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose([p.effort for p in message.points], tau, rtol=1e-9, atol=1e-8)
    stamps = [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in message.points]
    approach = approach_duration(build_excitation(result_problem(panda_runs["rest"])))
    np.testing.assert_allclose(stamps, time + approach, atol=1e-9)  # the first point after the approach
    assert f"first point (home, at rest) at {approach:g} s" in result.output


def test_the_approach_brings_the_robot_home_from_anywhere_in_its_range_within_the_limits(panda_runs):
    """The controller samples a first point at time 0 at once (joint_trajectory_controller's
    trajectory.cpp): a step from where the robot stands. Given the approach, its quintic from rest
    anywhere in the joint range to home at rest keeps the config's velocity and acceleration limits,
    sampled here (s ∈ [0, 1], 10 s³ − 15 s⁴ + 6 s⁵), and a tenth less would not."""
    excitation = build_excitation(result_problem(panda_runs["rest"]))
    approach, robot, limits = approach_duration(excitation), excitation.robot, excitation.limits
    farthest = np.maximum(robot.upper - robot.home, robot.home - robot.lower)
    s = np.linspace(0.0, 1.0, 20001)[:, None]

    def peaks(duration):
        speed = farthest * (30 * s**2 - 60 * s**3 + 30 * s**4) / duration
        acceleration = farthest * (60 * s - 180 * s**2 + 120 * s**3) / duration**2
        return np.abs(speed).max(axis=0) / limits.upper[1], np.abs(acceleration).max(axis=0) / limits.upper[2]

    assert max(peaks(approach)[0].max(), peaks(approach)[1].max()) <= 1.0 + 1e-9
    assert max(peaks(0.9 * approach)[0].max(), peaks(0.9 * approach)[1].max()) > 1.0


@pytest.fixture(scope="module")
def panda_played(panda_runs):
    """The rest run's first iteration as export plays it, at 200 Hz: ``play(speed, approach)``."""
    excitation = build_excitation(result_problem(panda_runs["rest"]))
    alpha = dict(read_alphas(panda_runs["rest"]))[1]
    return excitation, lambda speed=1.0, approach=None: export_trajectory(
        excitation, alpha, Played(panda_runs["rest"], 1, 200.0, 1, speed, approach)
    )


def test_a_shorter_approach_brings_home_only_a_robot_within_its_reach_of_it(panda_played):
    """Half a second: the quintic over each joint's reach peaks at its velocity or acceleration limit
    (sampled, as above), 1 % farther passes it; the export names those joints and the time needed."""
    excitation, play = panda_played
    limits, s = excitation.limits, np.linspace(0.0, 1.0, 20001)[:, None]
    reach = approach_reach(excitation, 0.5)

    def peak(distance):
        speed = np.abs(distance * (30 * s**2 - 60 * s**3 + 30 * s**4) / 0.5).max(axis=0) / limits.upper[1]
        acceleration = np.abs(distance * (60 * s - 180 * s**2 + 120 * s**3) / 0.25).max(axis=0) / limits.upper[2]
        return np.maximum(speed, acceleration)

    np.testing.assert_allclose(peak(reach), 1.0, rtol=1e-6)
    assert np.all(peak(1.01 * reach) > 1.0)
    played = play(approach=0.5)
    assert played.approach_needed == approach_duration(excitation) > 0.5
    assert [name for name, _ in played.reach] == excitation.robot.joint_names
    assert not play().reach  # the default reaches home from anywhere


def test_a_speed_the_limits_refuse_names_the_joint_and_the_largest_speed_that_passes(panda_played):
    _, play = panda_played
    with pytest.raises(ExciteError) as refused:
        play(speed=3.0)
    message = refused.value.problem
    assert re.search(r"violates joint_limits: \w+ of panda_joint\d at [\d.]+ of its half-range", message), message
    fastest = float(re.search(r"the largest speed that passes: ([\d.]+);", message).group(1))
    assert 1.0 <= fastest < 3.0
    assert play(speed=fastest).max_violation <= 0.0
    with pytest.raises(ExciteError):
        play(speed=fastest + 0.02)


def _csv(path):
    """time (S,), q, q̇, q̈, τ (S, n) of an ``excite export`` CSV."""
    table = np.genfromtxt(path, delimiter=",", skip_header=1)  # the column names, then the rows; notes last
    n = (table.shape[1] - 1) // 4
    return (table[:, 0], *(table[:, 1 + k * n : 1 + (k + 1) * n] for k in range(4)))


@pytest.mark.parametrize(
    "args, message",
    [
        (["-k", "9"], "--iteration"),
        (["--rate", "0"], "--rate"),
        (["--periods", "0"], "--periods"),
        (["--speed", "0"], "--speed"),
        (["--speed", "3"], "joint_limits"),
        (["--rate", "100000", "--periods", "1000"], "samples"),
    ],
)
def test_export_rejects_bad_options_without_writing(panda_runs, tmp_path, args, message):
    target = tmp_path / "x.csv"
    run = runner.invoke(app, ["export", str(panda_runs["rest"]), *args, "-o", str(target)])
    assert run.exit_code == 2 and message in run.output and "Traceback" not in run.output
    assert not target.exists() and not target.with_name(".x.csv.partial").exists()


def test_export_of_a_file_that_is_not_a_result(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f["regressor"] = np.zeros((3, 3))
    run = runner.invoke(app, ["export", str(path)])
    assert run.exit_code == 2 and "not an excite optimize result" in run.output


def test_quintic_meets_both_end_states_and_is_smooth():
    rng = np.random.default_rng(1)
    start, end = rng.normal(size=(3, 4)), rng.normal(size=(3, 4))
    transition = Transition(start, end, 1.7)
    q, qd, qdd = transition.evaluate(np.array([0.0, 1.7]))
    assert np.allclose(np.stack([q[0], qd[0], qdd[0]]), start, atol=1e-12)
    assert np.allclose(np.stack([q[1], qd[1], qdd[1]]), end, atol=1e-12)
    t = np.linspace(0.0, 1.7, 20001)
    q, qd, qdd = transition.evaluate(t)
    assert np.allclose(np.gradient(q, t, axis=0)[5:-5], qd[5:-5], atol=1e-6)
    assert np.allclose(np.gradient(qd, t, axis=0)[5:-5], qdd[5:-5], atol=1e-6)


def test_rest_to_rest_transition_is_as_short_as_the_velocity_limit_allows():
    basis_time = np.linspace(0.0, 1.0, 3)
    from excite_cli.trajectory.fourier import FourierTrajectory

    limits = JointLimits(
        np.array([[-3.0], [-1.0], [-100.0]]),
        np.array([[3.0], [1.0], [100.0]]),
        FourierTrajectory(1, 1.0).basis(basis_time),
    )
    start, end = np.zeros((3, 1)), np.zeros((3, 1))
    end[0, 0] = 2.0
    transition = plan_transition(start, end, limits, "test")
    shortest = 15.0 * 2.0 / (8.0 * (1.0 - GRID_MARGIN))  # minimum-jerk peak speed 15Δ/(8D)
    assert shortest <= transition.duration < shortest + RESOLUTION + 1e-12
    _, qd, _ = transition.evaluate(np.linspace(0.0, transition.duration, 2001))
    assert np.abs(qd).max() <= 1.0 - GRID_MARGIN + 1e-12
    assert plan_transition(start, start, limits, "none") is None


def test_a_standing_robot_s_transition_is_slowed_until_its_zero_moment_point_holds(g1_problem):
    """The G1 problem with its arms' limits at 40 rad/s and 400 rad/s²: brought from home to both arms
    stretched forward as fast as those limits allow, the ZMP leaves the soles (excite's ZMP, which
    tests/bench/test_mujoco_stance.py holds against MuJoCo's contact forces); the transition planned with it
    takes longer and keeps it."""
    g1_problem.limits.velocity, g1_problem.limits.acceleration = 40.0, 400.0
    excitation = build_excitation(g1_problem)
    zmp = next(c for c in excitation.constraints if c.eased_by_slowing)
    start = np.zeros((3, excitation.robot.n_joints))
    start[0] = excitation.home
    end = start.copy()
    for k, joint in enumerate(excitation.robot.joint_names):
        if "shoulder_pitch" in joint:
            end[0, k] = -1.5  # both arms stretched forward
    fast = plan_transition(start, end, excitation.limits, "fast")
    slowed = plan_transition(start, end, excitation.limits, "slowed", [zmp])

    def margin(transition):
        t = np.linspace(0.0, transition.duration, 400)
        return zmp.check_samples(t, *transition.evaluate(t)).details["zmp_min_margin_m"]

    assert margin(fast) < zmp.margin < margin(slowed) and slowed.duration > fast.duration
