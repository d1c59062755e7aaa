"""Joint limits (Eq. 51): aggregated values, their Jacobian, conservativeness and the fine re-check."""

import numpy as np
import pytest
from conftest import small

from excite_cli.constraints.joint_limits import JointLimits
from excite_cli.constraints.lse import GRID_MARGIN, SHARPNESS
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import constraint_jacobian_error


@pytest.fixture
def panda(panda_problem):
    return build_excitation(small(panda_problem))


def test_jacobian_matches_finite_differences(panda):
    alpha = panda.limits.random_start(panda.trajectory.n_coefficients, np.random.default_rng(0), 0.95)
    assert constraint_jacobian_error(panda.limits, alpha) < 1e-6


def test_aggregate_is_conservative_and_tight(panda):
    limits = panda.limits
    rng = np.random.default_rng(1)
    for _ in range(5):
        alpha = limits.random_start(panda.trajectory.n_coefficients, rng, rng.uniform(0.3, 0.99))
        alpha[:, 1:] *= rng.uniform(0.8, 1.3)  # some beyond the limits
        g = limits.evaluate(alpha)[0].reshape(6, -1)
        z = np.stack(
            [
                (B @ alpha.T - limits.centre[d]) / limits.half[d]
                for d, B in enumerate((panda.grid_basis.q, panda.grid_basis.qd, panda.grid_basis.qdd))
            ]
        )
        exact = np.concatenate([z.max(axis=1) - 1.0, -z.min(axis=1) - 1.0])
        assert np.all(g >= exact + GRID_MARGIN - 1e-12)
        assert np.all(g <= exact + GRID_MARGIN + np.log(z.shape[1]) / SHARPNESS)


def test_random_start_fills_the_requested_fraction(panda):
    alpha = panda.limits.random_start(panda.trajectory.n_coefficients, np.random.default_rng(2), 0.6)
    check = panda.limits.check(alpha, panda.grid_basis)
    assert check.max_violation == pytest.approx(-0.4, abs=1e-9)


def test_fine_check_reports_physical_violation():
    basis_times = np.linspace(0, 2 * np.pi, 2001)
    from excite_cli.trajectory.fourier import FourierTrajectory

    basis = FourierTrajectory(1, 1.0).basis(basis_times)
    lower = np.array([[-1.0], [-1.0], [-1.0]])
    upper = np.array([[1.0], [1.0], [1.0]])
    limits = JointLimits(lower, upper, basis)
    check = limits.check(np.array([[0.0, 1.2, 0.0]]), basis)  # q = 1.2 sin t
    assert check.details["max_violation_position_rad"] == pytest.approx(0.2, abs=1e-6)
    assert check.max_violation == pytest.approx(0.2, abs=1e-6)


def test_restore_repairs_a_violating_trajectory_minimally(panda):
    limits = panda.limits
    rng = np.random.default_rng(4)
    alpha = limits.random_start(panda.trajectory.n_coefficients, rng, 0.9)
    alpha[:, 1:] *= 1.2  # 8% beyond the limits
    alpha[0, 0] = limits.upper[0, 0] + 0.3  # offset outside the range
    assert limits.check(alpha, panda.grid_basis).max_violation > 0
    repaired = limits.restore(alpha)
    check = limits.check(repaired, panda.grid_basis)
    assert check.max_violation == pytest.approx(-GRID_MARGIN, abs=1e-9)
    # joints that were inside stay untouched up to the common scale; shapes are kept
    ratio = repaired[:, 1:] / alpha[:, 1:]
    assert np.allclose(ratio, ratio[:, :1])


def test_a_per_joint_position_margin_narrows_that_joint_alone(ur5_problem):
    """limits.position_margin {joint: rad}: that joint's range is the URDF's (pinocchio's model of the
    URDF, read here) narrowed by its margin at each end; the other joints keep the URDF's whole range."""
    import pinocchio as pin

    from excite_cli.constraints.joint_limits import joint_limit_bounds
    from excite_cli.dynamics.robot import load_robot
    from excite_cli.dynamics.robot_files import example_robot_data_root

    ur5_problem.limits.position_margin = {"elbow_joint": 0.6283}
    robot = load_robot(ur5_problem.robot, ur5_problem.folder, False)
    lower, upper = joint_limit_bounds(ur5_problem.limits, robot)
    urdf = example_robot_data_root() / "example-robot-data" / "robots" / ur5_problem.robot.urdf
    model = pin.buildModelFromUrdf(str(urdf))
    for k, name in enumerate(robot.joint_names):
        index = model.idx_qs[model.getJointId(name)]
        margin = 0.6283 if name == "elbow_joint" else 0.0
        assert lower[0, k] == pytest.approx(model.lowerPositionLimit[index] + margin)
        assert upper[0, k] == pytest.approx(model.upperPositionLimit[index] - margin)


def test_a_velocity_limit_the_joint_cannot_reach_is_warned_about_with_the_likely_unit(ur5_problem):
    """62 deg/s meant as rad/s on the UR5 (URDF: 3.15 rad/s): 19.7 times the URDF's, deg/s named; 1.5
    rad/s (below the URDF's, as the shipped config) says nothing."""
    import warnings

    from excite_cli.constraints.joint_limits import joint_limit_bounds
    from excite_cli.dynamics.robot import load_robot
    from excite_cli.errors import ExciteWarning

    robot = load_robot(ur5_problem.robot, ur5_problem.folder, False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ur5_problem.limits.velocity = 1.5
        joint_limit_bounds(ur5_problem.limits, robot)
        assert caught == []
        ur5_problem.limits.velocity = {"elbow_joint": 62.0}
        joint_limit_bounds(ur5_problem.limits, robot)
    (warning,) = [w for w in caught if issubclass(w.category, ExciteWarning)]
    urdf = robot.velocity_limit[robot.joint_names.index("elbow_joint")]
    assert f"62 rad/s for joint 'elbow_joint' is {62.0 / urdf:.3g} times the URDF's" in str(warning.message)
    assert "deg/s?" in str(warning.message)


def test_a_prismatic_joint_s_velocity_limit_is_warned_about_in_m_per_s():
    """The Panda's finger (URDF: 0.2 m/s) given 5: the warning speaks of m/s and suggests no deg/s."""
    import warnings

    from excite_cli.config import LimitsConfig, RobotConfig
    from excite_cli.constraints.joint_limits import joint_limit_bounds
    from excite_cli.dynamics.robot import load_robot
    from excite_cli.errors import ExciteWarning

    finger = RobotConfig(
        urdf="panda_description/urdf/panda.urdf",
        source="example-robot-data",
        active_joints=["panda_finger_joint1"],
        locked_joints={"panda_finger_joint2": 0.0},
    )
    robot = load_robot(finger)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        joint_limit_bounds(LimitsConfig(velocity={"panda_finger_joint1": 5.0}, acceleration=1.0), robot)
    (warning,) = [w for w in caught if issubclass(w.category, ExciteWarning)]
    assert (
        "5 m/s for joint 'panda_finger_joint1' is 25 times the URDF's 0.2 m/s" == str(warning.message).split(": ", 1)[1]
    )
