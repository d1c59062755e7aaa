"""Base parameters (Eq. 2): Y_B φ_B must reproduce pinocchio's RNEA torques at fresh random states."""

import os
import platform
import subprocess
import sys

import numpy as np
import pinocchio as pin
import pytest
from conftest import CONFIGS, robot_of

from excite_cli.dynamics.base_parameters import (
    base_from_regressor,
    compute_base_parameters,
    pivoted_columns,
    rotor_regrouping,
)


@pytest.mark.parametrize("name", ["g1_problem", "panda_problem", "ur5_problem"])
def test_base_regressor_reproduces_rnea(name, request):
    robot = robot_of(request.getfixturevalue(name))
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
    robot = robot_of(request.getfixturevalue(name))
    base = compute_base_parameters(robot)
    W = robot.regressor_stack(*robot.random_states(60, np.random.default_rng(7)))
    assert base.count == np.linalg.matrix_rank(W)
    assert np.linalg.matrix_rank(W @ base.composition_matrix) == base.count


@pytest.mark.parametrize(("name", "regrouped"), [("panda_problem", 2), ("ur5_problem", 2), ("g1_problem", 4)])
def test_rotor_regrouping_is_the_armature_pinocchio_adds(name, regrouped, request):
    """Y_B R a equals what pinocchio's RNEA adds with armature a on the joints R says regroup (a serial
    arm's first two, each of the G1's shoulder pitch and roll); the others' armature is no combination
    of the base parameters' columns."""
    robot = robot_of(request.getfixturevalue(name))
    base = compute_base_parameters(robot)
    R = rotor_regrouping(robot, base)
    held = np.flatnonzero(np.abs(R).sum(axis=0) > 0)
    assert held.size == regrouped
    rng = np.random.default_rng(11)
    armature = np.zeros(robot.n_joints)
    armature[held] = rng.uniform(0.1, 0.5, held.size)
    geared = pin.Model(robot.model)
    geared.armature[robot.v_idx] = armature
    data = geared.createData()
    Q, QD, QDD = robot.random_states(40, rng)
    for q, qd, qdd in zip(Q[:10], QD[:10], QDD[:10]):
        added = pin.rnea(geared, data, *robot.state(q, qd, qdd))[robot.row_idx] - robot.torques(q, qd, qdd)
        np.testing.assert_allclose(
            robot.regressor(q, qd, qdd) @ base.composition_matrix @ R @ armature, added, atol=1e-9
        )
    Y_B = robot.regressor_stack(Q, QD, QDD) @ base.composition_matrix
    first = robot.n_rows - robot.n_joints
    for j in sorted(set(range(robot.n_joints)) - set(held)):
        column = np.zeros((len(Q), robot.n_rows))
        column[:, first + j] = QDD[:, j]
        column = column.ravel()
        residual = column - Y_B @ np.linalg.lstsq(Y_B, column, rcond=None)[0]
        assert np.linalg.norm(residual) > 0.1 * np.linalg.norm(column)


def test_panda_count_matches_the_literature(panda_problem):
    # A 7R arm with a vertical first axis and no parallel consecutive axes has 7n - 6 = 43 base
    # parameters (Gautier 1991); Gaz et al. (RA-L 2019) identify 43 for the Panda.
    assert compute_base_parameters(robot_of(panda_problem)).count == 43


def test_names_say_what_is_regrouped(panda_problem):
    base = compute_base_parameters(robot_of(panda_problem))
    assert len(base.names) == base.count
    assert any("+" in name or " - " in name for name in base.names)


def _random_regressor(robot, seed=0):
    return robot.regressor_stack(*robot.random_states(40, np.random.default_rng(seed)))


@pytest.mark.parametrize("name", ["g1_problem", "panda_problem", "ur5_problem"])
def test_the_base_does_not_depend_on_the_order_of_rows_or_columns(name, request):
    # Ties (the G1's two arms, the regrouping rules) are broken by the parameters' order, not by
    # where a column sits or by rounding: permuted rows and columns give the same parameters.
    robot = robot_of(request.getfixturevalue(name))
    W, names = _random_regressor(robot), robot.parameter_names
    base = base_from_regressor(W, names)
    rng = np.random.default_rng(1)
    rows, columns = rng.permutation(W.shape[0]), rng.permutation(W.shape[1])
    by_rows = base_from_regressor(W[rows], names)
    by_columns = base_from_regressor(W[:, columns], [names[k] for k in columns], order=columns)
    assert by_rows.names == base.names
    assert sorted(columns[by_columns.independent]) == sorted(base.independent)
    assert sorted(by_columns.names) == sorted(base.names)


def test_tied_columns_go_to_the_first_parameter():
    # Two columns of equal norm in exact arithmetic (the mirror of each other): the first in the
    # parameter order wins, wherever it sits.
    rng = np.random.default_rng(3)
    a, c = rng.standard_normal(30), rng.standard_normal(30)
    W = np.column_stack([a, -a, c])
    assert sorted(pivoted_columns(W, np.array([0, 1, 2]))) == [0, 2]
    assert sorted(pivoted_columns(W, np.array([1, 0, 2]))) == [1, 2]
    assert sorted(pivoted_columns(W[:, [1, 0, 2]], np.array([1, 0, 2]))) == [1, 2]  # column 1 there is parameter 0


_BASE_NAMES = (
    "import sys, hashlib; from excite_cli.config_file import load_problem; "
    "from excite_cli.dynamics.robot import load_robot; "
    "from excite_cli.dynamics.base_parameters import compute_base_parameters; "
    "p = load_problem(sys.argv[1]); b = compute_base_parameters(load_robot(p.robot, p.folder)); "
    "print(hashlib.sha256(('|'.join(b.names)).encode() + b.regrouping.tobytes()).hexdigest())"
)


@pytest.mark.skipif(platform.machine() != "x86_64", reason="OpenBLAS core types named here are x86_64's")
@pytest.mark.parametrize("config", ["g1_arms.yaml", "panda.yaml", "ur5.yaml"])
def test_the_base_is_the_same_with_every_blas_kernel_and_thread_count(config):
    # Plain pivoted QR gave three bases of the G1 on one machine (AVX-512 with 1 or 2 threads, AVX2).
    digests = set()
    for env in ({}, {"OPENBLAS_NUM_THREADS": "1"}, {"OPENBLAS_CORETYPE": "Haswell"}, {"OPENBLAS_CORETYPE": "Prescott"}):
        run = subprocess.run(
            [sys.executable, "-c", _BASE_NAMES, str(CONFIGS / config)],
            env={**os.environ, **env},
            capture_output=True,
            text=True,
            check=True,
        )
        digests.add(run.stdout.strip())
    assert len(digests) == 1
