"""Torques a fit should not be trusted with: the Panda's own URDF torques at random states, then the
same torques with one joint's sign flipped, one in mNm, and friction only (no warning there)."""

import numpy as np
import pytest
from conftest import CONFIGS, robot_of

from excite_cli.config_file import load_problem
from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.plausibility import negative_masses, urdf_disagreements


@pytest.fixture(scope="module")
def panda_data():
    """(Dataset of the URDF's own torques plus 5 % noise, URDF base parameters, joint names)."""
    robot = robot_of(load_problem(CONFIGS / "panda_joint_limits.yaml"))
    base = compute_base_parameters(robot)
    rng = np.random.default_rng(3)
    q, qd, qdd = robot.random_states(200, rng)
    Y = np.vstack([robot.regressor(*s) for s in zip(q, qd, qdd)]) @ base.composition_matrix
    urdf = base.from_standard(robot.urdf_parameters())
    tau = Y @ urdf
    tau = tau + 0.05 * np.std(tau) * rng.standard_normal(tau.size)
    return Dataset(Y, tau, np.arange(200) * 0.01, np.zeros(200, dtype=int), {}), urdf, robot.joint_names


def _with(data: Dataset, joint: int, factor: float) -> Dataset:
    tau = data.tau.copy()
    tau[joint :: data.n] *= factor
    return Dataset(data.regressor, tau, data.time, data.run, {})


def test_torques_the_urdf_explains_raise_nothing(panda_data):
    data, urdf, joints = panda_data
    assert urdf_disagreements(data, urdf, joints) == []
    assert urdf_disagreements(_with(data, 1, 1.8), urdf, joints) == []  # a URDF 80 % off is rough, not wrong


def test_a_flipped_sign_is_named_with_its_joint_and_field(panda_data):
    data, urdf, joints = panda_data
    (line,) = urdf_disagreements(_with(data, 1, -1.0), urdf, joints)
    assert line.startswith("panda_joint2: the measured torque runs against the URDF model's (slope -1.0")
    assert "data.signs" in line


def test_torques_in_another_unit_are_named(panda_data):
    data, urdf, joints = panda_data
    (line,) = urdf_disagreements(_with(data, 3, 1000.0), urdf, joints)  # mNm
    assert line.startswith("panda_joint4: the measured torque is 1e+03 times the URDF model's")
    assert "data.columns.factors" in line


def test_friction_only_torque_is_not_called_a_sign(panda_data):
    """A joint whose torque the URDF does not explain (|cos| < 0.7) is left alone."""
    data, urdf, joints = panda_data
    tau = data.tau.copy()
    tau[6 :: data.n] = np.sign(np.sin(np.arange(200)))  # a Coulomb-like square wave, unrelated to the model
    assert urdf_disagreements(Dataset(data.regressor, tau, data.time, data.run, {}), urdf, joints) == []


def test_negative_masses_are_named_with_the_likely_cause():
    standard = np.zeros(20)
    standard[0], standard[10] = 2.0, -3.8
    (line,) = negative_masses(standard, ["upper", "lower"], [])
    assert "lower (-3.8 kg)" in line and "upper" not in line and "excitation" in line
    (line,) = negative_masses(standard, ["upper", "lower"], ["lower_joint: ... a flipped sign?"])
    assert "torque signs or units" in line
    assert negative_masses(np.abs(standard), ["upper", "lower"], []) == []
