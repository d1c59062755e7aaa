"""Boundary conditions (rest at both ends, home at both ends) as exact coordinates of the optimizer."""

import numpy as np
import pytest
from conftest import CONFIGS, small

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.errors import ExciteError
from excite_cli.trajectory.boundary import BoundaryConditions, boundary_rows
from excite_cli.trajectory.fourier import FourierTrajectory


def _excitation(boundary="rest", ends_at_home=False, duration=None, harmonics=4):
    problem = small(load_problem(CONFIGS / "panda_joint_limits.yaml"), harmonics=harmonics)
    problem.trajectory.boundary = boundary
    problem.trajectory.ends_at_home = ends_at_home
    if duration is not None:  # a duration that is not a whole period: four distinct rest rows
        problem.trajectory.cost_period = duration / problem.trajectory.cost_samples
    return build_excitation(problem)


def _ends(excitation, alpha):
    T = excitation.spec.trajectory.duration
    return excitation.trajectory.basis(np.array([0.0, T])).evaluate(alpha)


@pytest.mark.parametrize("duration", [10.0, 7.3])
def test_every_point_of_the_coordinates_is_at_rest_at_both_ends(duration):
    excitation = _excitation(duration=duration)
    boundary = excitation.boundary
    rng = np.random.default_rng(0)
    for _ in range(5):
        alpha = boundary.to_alpha(rng.normal(size=boundary.size))
        _, qd, qdd = _ends(excitation, alpha)
        assert np.abs(qd).max() < 1e-12 and np.abs(qdd).max() < 1e-11
    expected = 7 * (9 - (2 if duration == 10.0 else 4))  # T = 10 s is the period: its rows repeat those at t = 0
    assert boundary.size == expected


def test_home_at_both_ends():
    excitation = _excitation(ends_at_home=True, duration=7.3)
    alpha = excitation.boundary.to_alpha(np.random.default_rng(1).normal(size=excitation.boundary.size))
    q, qd, qdd = _ends(excitation, alpha)
    assert np.abs(q - excitation.home).max() < 1e-12 and np.abs(qd).max() < 1e-12
    start = excitation.random_start(np.random.default_rng(2))
    assert np.abs(_ends(excitation, start)[0] - excitation.home).max() < 1e-12


def test_coordinates_round_trip_and_projection():
    boundary = _excitation().boundary
    z = np.random.default_rng(3).normal(size=boundary.size)
    alpha = boundary.to_alpha(z)
    assert np.allclose(boundary.to_variables(alpha), z, atol=1e-12)
    assert np.allclose(boundary.project(alpha), alpha, atol=1e-12)
    off = alpha + np.random.default_rng(4).normal(size=alpha.shape)
    projected = boundary.project(off)
    assert np.allclose(boundary.project(projected), projected, atol=1e-12)


def test_periodic_coordinates_are_the_preconditioned_coefficients():
    excitation = _excitation("periodic")
    alpha = excitation.random_start(np.random.default_rng(5))
    assert np.allclose(excitation.boundary.to_variables(alpha), (alpha / excitation.limits.coefficient_scale()).ravel())


def test_chained_gradient_matches_finite_differences_in_the_coordinates():
    excitation = _excitation()
    boundary, criterion = excitation.boundary, excitation.criterion()
    z = boundary.to_variables(excitation.random_start(np.random.default_rng(6)))
    _, grad = criterion.value_and_gradient(boundary.to_alpha(z))
    analytic = boundary.chain(grad.ravel())
    h = 1e-6
    numeric = np.array(
        [
            (criterion.value(boundary.to_alpha(z + h * e)) - criterion.value(boundary.to_alpha(z - h * e))) / (2 * h)
            for e in np.eye(z.size)
        ]
    )
    assert np.linalg.norm(analytic - numeric) / np.linalg.norm(numeric) < 1e-6
    # a constraint without rows (self-collision on a robot with one capsule: no pair) chains to none
    rows = boundary.chain(np.zeros((0, grad.size)))
    assert rows.shape == (0, z.size)


def test_random_starts_are_at_rest_and_feasible():
    excitation = _excitation(duration=7.3)
    for seed in range(3):
        alpha = excitation.random_start(np.random.default_rng(seed))
        _, qd, qdd = _ends(excitation, alpha)
        assert np.abs(qd).max() < 1e-12 and np.abs(qdd).max() < 1e-11
        assert all(c.accepts(alpha) for c in excitation.constraints)
        assert np.abs(alpha[:, 1:]).max() > 0.01  # it moves


def test_too_few_harmonics_for_rest_is_a_config_error():
    with pytest.raises(ExciteError, match="trajectory.harmonics"):
        _excitation(harmonics=1)


def test_rows_are_the_fourier_basis_of_velocity_acceleration_and_position_at_both_ends():
    trajectory = FourierTrajectory(3, 0.7)
    rows = boundary_rows(trajectory, 5.0, rest=True, at_home=True)
    ends = trajectory.basis(np.array([0.0, 5.0]))
    expected = np.vstack([ends.qd, ends.qdd, ends.q])  # q̇, q̈ at 0 and T, then q at 0 and T
    assert rows.shape == expected.shape
    for row in expected:
        assert np.min(np.abs(rows - row).max(axis=1)) < 1e-12
    conditions = BoundaryConditions(rows, np.zeros((2, rows.shape[0])), np.ones((2, 7)))
    alpha = conditions.to_alpha(np.random.default_rng(0).standard_normal(conditions.size))
    np.testing.assert_allclose(alpha @ rows.T, 0.0, atol=1e-12)  # every point of the coordinates meets them
