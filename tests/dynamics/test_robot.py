"""Loading a robot from its config section: the active joints, locked joints at their values, the
regressor rows, a URDF given by path, and unknown joints named."""

import numpy as np
import pinocchio as pin
import pytest
from conftest import CONFIGS, GOOD, PENDULUM

from excite_cli.config_file import load_problem
from excite_cli.dynamics.robot import load_robot
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.errors import ExciteError


def test_rows_are_the_joints_and_with_base_wrench_rows_the_base_too():
    cfg = load_problem(CONFIGS / "g1_arms.yaml").robot.model_copy(update={"base_wrench_rows": True})
    assert load_robot(cfg).n_rows == 6 + 14
    robot = load_robot(cfg, joint_rows_only=True)
    assert robot.n_rows == robot.n_joints == 14
    q, qd, qdd = robot.random_states(1, np.random.default_rng(0))
    full = pin.rnea(robot.model, robot.model.createData(), *robot.state(q[0], qd[0], qdd[0]))
    np.testing.assert_allclose(robot.torques(q[0], qd[0], qdd[0]), full[robot.v_idx], atol=1e-12)


def test_locked_joints_sit_at_their_values_and_a_given_urdf_replaces_the_section_s(tmp_path):
    (tmp_path / "pendulum.urdf").write_text(PENDULUM.format(**{**GOOD, "mimic": ""}))
    heavier = tmp_path / "heavier.urdf"
    heavier.write_text(PENDULUM.format(**{**GOOD, "mimic": "", "mass": "3.0"}))
    section = {
        "urdf": "pendulum.urdf",
        "source": "file",
        "active_joints": ["hinge"],
        "locked_joints": {"tip_joint": 0.5},
    }
    cfg = load_problem(CONFIGS / "smoke.yaml").robot.model_copy(update=section)
    assert resolve_urdf(cfg, tmp_path)[0] == tmp_path / "pendulum.urdf"
    robot, other = load_robot(cfg, tmp_path), load_robot(cfg, tmp_path, urdf=heavier)
    assert robot.joint_names == other.joint_names == ["hinge"] and robot.model.nq == 1
    q, zero = np.array([0.3]), np.zeros(1)
    full = pin.buildModelFromUrdf(str(tmp_path / "pendulum.urdf"))  # both joints, the tip at 0.5 rad
    expected = pin.rnea(full, full.createData(), np.array([0.3, 0.5]), np.zeros(2), np.zeros(2))[0]
    assert robot.torques(q, zero, zero)[0] == pytest.approx(expected, rel=1e-12)
    assert abs(other.torques(q, zero, zero)[0]) > abs(expected)  # the 3 kg arm of the given URDF


def test_an_unknown_joint_is_named_with_the_nearest_one():
    cfg = load_problem(CONFIGS / "smoke.yaml").robot
    with pytest.raises(ExciteError, match="panda_joint77"):
        load_robot(cfg.model_copy(update={"active_joints": ["panda_joint1", "panda_joint77"]}))


def test_states_of_many_samples_are_each_sample_s_state():
    robot = load_robot(load_problem(CONFIGS / "g1_arms.yaml").robot)
    samples = np.random.default_rng(4).standard_normal((3, 5, robot.n_joints))
    for batch, single in zip(robot.states(*samples), zip(*(robot.state(*x) for x in zip(*samples)))):
        np.testing.assert_array_equal(batch, np.array(single))
