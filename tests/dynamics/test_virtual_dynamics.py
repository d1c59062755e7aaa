"""Weighted RNEA derivatives with virtual parameters: the mass shift changes no torque derivative,
and passes per regressor row equal passes per parameter vector."""

import numpy as np
import pinocchio as pin
import pytest
from conftest import small

from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.virtual_dynamics import VirtualDynamics


@pytest.mark.parametrize("name, base_rows", [("g1_problem", False), ("g1_problem", True), ("panda_problem", False)])
def test_mass_shift_changes_no_torque_with_the_motion(name, base_rows, request):
    """φ_s (point masses on the joint axes, cancelled on the parents) keeps every body massive and
    adds nothing to ∂τ/∂(q, q̇, q̈), so the gradient needs no pass of its own."""
    problem = small(request.getfixturevalue(name), harmonics=3, samples=8)
    problem.robot.base_wrench_rows = base_rows
    robot = build_excitation(problem).robot
    dynamics = VirtualDynamics(robot)
    assert dynamics.model.nv == robot.n_joints + (
        6 if base_rows else 0
    )  # the held base is locked unless its wrench is a row
    models, datas = dynamics._virtual_models(np.zeros((robot.n_parameters, 1)))
    assert len(models) == 1 and all(models[0].inertias[j].mass > 0.5 for j in range(1, models[0].njoints))
    for q, qd, qdd in zip(*robot.random_states(5, np.random.default_rng(0))):
        state = np.tile(dynamics.q_reference, 1), np.zeros(dynamics.model.nv), np.zeros(dynamics.model.nv)
        state[0][dynamics.q_idx], state[1][dynamics.v_idx], state[2][dynamics.v_idx] = q, qd, qdd
        for d in pin.computeRNEADerivatives(models[0], datas[0], *state):
            assert np.abs(d[dynamics.row_idx][:, dynamics.v_idx]).max() < 1e-9


@pytest.mark.parametrize("name, base_rows, prismatic", [("g1_problem", True, False), ("panda_problem", False, True)])
def test_passes_per_row_equal_passes_per_parameter(name, base_rows, prismatic, request):
    """Full-rank weights (D-optimality) take a virtual parameter per instant and row, rows of disjoint
    subtrees in one pass: the same derivatives as one pass per parameter vector with row weights."""
    problem = small(request.getfixturevalue(name), harmonics=3, samples=6)
    problem.robot.base_wrench_rows = base_rows
    if prismatic:
        problem.robot.active_joints = [*problem.robot.active_joints[:3], "panda_finger_joint1"]
        problem.robot.locked_joints.pop("panda_finger_joint1", None)
        problem.robot.locked_joints["panda_finger_joint2"] = 0.0  # it mimics finger 1: held on purpose
        problem.limits.position_margin = 0.002
    robot = build_excitation(problem).robot
    dynamics = VirtualDynamics(robot)
    rng = np.random.default_rng(0)
    Q, QD, QDD = robot.random_states(6, rng)
    phis, weights = rng.standard_normal((robot.n_parameters, 4)), rng.standard_normal((4, 6, robot.n_rows))
    expected = dynamics.weighted_derivatives(phis, weights, Q, QD, QDD)
    per_row = dynamics.row_derivatives(np.einsum("rtk,pr->tkp", weights, phis), Q, QD, QDD)
    for a, b in zip(per_row, expected):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * np.abs(b).max())
    assert len(dynamics.slots) == (6 + 7 if base_rows else robot.n_rows)  # the G1's arms share passes
