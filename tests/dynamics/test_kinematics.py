"""Forward kinematics of all grid instants at once, and the rate of a distance along a normal,
against pinocchio."""

import numpy as np
import pinocchio as pin
import pytest
from conftest import CONFIGS, TESTS

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.kinematics import BatchKinematics


@pytest.fixture(scope="module")
def panda():
    return build_excitation(load_problem(TESTS / "panda_capsules.yaml"))


@pytest.fixture(scope="module")
def g1():
    problem = load_problem(CONFIGS / "g1_arms.yaml")
    problem.trajectory.harmonics, problem.trajectory.cost_samples = 3, 10
    problem.trajectory.cost_period, problem.trajectory.constraint_period = 0.8, 0.1
    return build_excitation(problem)


def _lively(excitation, seed):
    return excitation.limits.random_start(
        excitation.trajectory.n_coefficients, np.random.default_rng(seed), 0.9, excitation.home
    )


@pytest.mark.parametrize("robot", ["panda", "g1"])
def test_batched_kinematics_equal_pinocchio(robot, request):
    excitation = request.getfixturevalue(robot)
    model, kinematics = excitation.robot.model, BatchKinematics(excitation.robot)
    data = model.createData()
    Q = excitation.grid_basis.q @ _lively(excitation, 4).T
    R, p = kinematics.placements(Q)
    for t in range(0, Q.shape[0], 5):
        state = excitation.robot.state(Q[t], 0 * Q[t], 0 * Q[t])[0]
        pin.computeJointJacobians(model, data, state)
        for j in range(1, model.njoints):
            np.testing.assert_allclose(R[t, j], data.oMi[j].rotation, atol=1e-12)
            np.testing.assert_allclose(p[t, j], data.oMi[j].translation, atol=1e-12)
        point, normal = p[t, -1] + [0.1, -0.05, 0.2], np.array([0.6, 0.0, 0.8])
        J = pin.getJointJacobian(model, data, model.njoints - 1, pin.LOCAL_WORLD_ALIGNED)[:, excitation.robot.v_idx]
        expected = normal @ (J[:3] - pin.skew(point - p[t, -1]) @ J[3:])
        got = kinematics.distance_rates(R[t : t + 1], p[t : t + 1], point[:, None, None], normal[:, None, None])
        np.testing.assert_allclose(got[0, 0] * kinematics.ancestors[-1], expected, atol=1e-12)
