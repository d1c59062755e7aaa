"""The reverse pass of RNEA against pinocchio: the gradient of Σ_k τ_k(x; φ_k) with one parameter vector
per row, checked against pinocchio's analytic RNEA derivatives (one physical φ, row weights) and against
central differences of pinocchio's regressor (a different φ per instant and row, any values)."""

import numpy as np
import pinocchio as pin
import pytest
from conftest import small

from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.regressor_adjoint import RegressorAdjoint


def _robot(request, name: str, base_rows: bool, prismatic: bool):
    problem = small(request.getfixturevalue(name), harmonics=3, samples=12)
    problem.robot.base_wrench_rows = base_rows
    if prismatic:
        problem.robot.active_joints = [*problem.robot.active_joints[:3], "panda_finger_joint1"]
        problem.robot.locked_joints.pop("panda_finger_joint1", None)
        problem.robot.locked_joints["panda_finger_joint2"] = 0.0  # it mimics finger 1: held on purpose
        problem.limits.position_margin = 0.002
    return build_excitation(problem).robot


CASES = [("g1_problem", False, False), ("g1_problem", True, False), ("panda_problem", False, True)]


@pytest.mark.parametrize("name, base_rows, prismatic", CASES)
def test_equals_pinocchio_rnea_derivatives_with_row_weights(name, base_rows, prismatic, request):
    """φ_{t,k} = w_{t,k} φ_URDF: the gradient is Σ_k w_{t,k} ∂τ_k(x_t; φ_URDF)/∂x_t, pinocchio's analytic
    RNEA derivatives of the robot's own model (held base and locked joints at the reference)."""
    robot = _robot(request, name, base_rows, prismatic)
    rng = np.random.default_rng(0)
    Q, QD, QDD = robot.random_states(5, rng)
    weights = rng.standard_normal((5, robot.n_rows))
    phis = weights[:, :, None] * robot.urdf_parameters()
    got = RegressorAdjoint(robot).row_derivatives(phis, Q, QD, QDD)
    data = robot.model.createData()
    for t in range(5):
        derivatives = pin.computeRNEADerivatives(robot.model, data, *robot.state(Q[t], QD[t], QDD[t]))
        for g, d in zip(got, derivatives):
            expected = weights[t] @ d[robot.row_idx][:, robot.v_idx]
            np.testing.assert_allclose(g[t], expected, rtol=0, atol=1e-12 * np.abs(expected).max())


@pytest.mark.parametrize("name, base_rows, prismatic", CASES)
def test_equals_central_differences_of_the_regressor(name, base_rows, prismatic, request):
    """Any φ per instant and row (no mass needed anywhere): g(x) = Σ_k Y_k(x) φ_k with pinocchio's
    regressor, differentiated by central differences in each of q, q̇, q̈."""
    robot = _robot(request, name, base_rows, prismatic)
    rng = np.random.default_rng(1)
    Q, QD, QDD = robot.random_states(3, rng)
    phis = rng.standard_normal((3, robot.n_rows, robot.n_parameters))
    got = RegressorAdjoint(robot).row_derivatives(phis, Q, QD, QDD)
    h = 1e-6
    for t in range(3):
        state = [Q[t], QD[t], QDD[t]]
        for which in range(3):
            for i in range(robot.n_joints):
                plus, minus = [x.copy() for x in state], [x.copy() for x in state]
                plus[which][i] += h
                minus[which][i] -= h
                g = [np.sum(robot.regressor(*x) * phis[t]) for x in (plus, minus)]
                fd = (g[0] - g[1]) / (2 * h)
                assert abs(got[which][t, i] - fd) <= 1e-6 * max(1.0, abs(fd))
