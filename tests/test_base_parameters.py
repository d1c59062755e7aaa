"""Base parameters (Eq. 2): Y_B φ_B must reproduce pinocchio's RNEA torques at fresh random states."""

import numpy as np
import pytest

from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.robot import load_robot


@pytest.mark.parametrize("name", ["g1_problem", "panda_problem", "ur5_problem"])
def test_base_regressor_reproduces_rnea(name, request):
    robot = load_robot(request.getfixturevalue(name))
    base = compute_base_parameters(robot)
    phi_b = base.from_standard(robot.urdf_parameters())
    Q, QD, QDD = robot.random_states(15, np.random.default_rng(123))
    for q, qd, qdd in zip(Q, QD, QDD):
        tau = robot.torques(q, qd, qdd)
        np.testing.assert_allclose(
            robot.regressor(q, qd, qdd) @ base.composition_matrix @ phi_b,
            tau,
            rtol=1e-8,
            atol=1e-8 * (1 + np.abs(tau).max()),
        )


@pytest.mark.parametrize("name", ["panda_problem", "ur5_problem"])
def test_number_of_base_parameters_is_the_regressor_rank(name, request):
    robot = load_robot(request.getfixturevalue(name))
    base = compute_base_parameters(robot)
    W = robot.regressor_stack(*robot.random_states(60, np.random.default_rng(7)))
    assert base.count == np.linalg.matrix_rank(W)
    assert np.linalg.matrix_rank(W @ base.composition_matrix) == base.count


def test_panda_count_matches_the_literature(panda_problem):
    # A 7R arm with a vertical first axis and no parallel consecutive axes has 7n - 6 = 43 base
    # parameters (Gautier 1991); Gaz et al. (RA-L 2019) identify 43 for the Panda.
    assert compute_base_parameters(load_robot(panda_problem)).count == 43


def test_names_say_what_is_regrouped(panda_problem):
    base = compute_base_parameters(load_robot(panda_problem))
    assert len(base.names) == base.count
    assert any("+" in name or " - " in name for name in base.names)
