"""Weighted least squares on the normal equations kept per joint, against the closed form; friction and
armature kept non-negative, against the optimality conditions of the bounded problem."""

import numpy as np

from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import least_squares, torque_errors
from excite_cli.identification.fitting.normal import NormalEquations, solve


def test_weighted_least_squares_and_standard_deviations_match_the_closed_form():
    rng = np.random.default_rng(0)
    N, n, b = 400, 2, 3
    Y = rng.standard_normal((N * n, b))
    x_true = np.array([1.0, -2.0, 0.5])
    sigma = np.array([0.1, 0.4])  # per joint
    tau = Y @ x_true + rng.standard_normal(N * n) * np.tile(sigma, N)
    data = Dataset(Y, tau, np.arange(N) * 0.01, np.zeros(N, dtype=int), {})
    weights = 1.0 / sigma
    fit = least_squares(NormalEquations(data, []), [], weights)
    W = np.tile(weights, N)
    A, y = W[:, None] * Y, W * tau
    x = np.linalg.solve(A.T @ A, A.T @ y)
    s2 = np.sum((y - A @ x) ** 2) / (N * n - b)
    np.testing.assert_allclose(fit.x, x, rtol=1e-10)
    np.testing.assert_allclose(fit.std, np.sqrt(s2 * np.diag(np.linalg.inv(A.T @ A))), rtol=1e-8)


def test_torque_errors_are_rms_per_joint_relative_to_the_torque():
    measured = np.array([[3.0, 0.0], [-3.0, 0.0]])
    predicted = np.array([[2.0, 1.0], [-4.0, -1.0]])
    rms, torque, relative = torque_errors(measured, predicted)
    np.testing.assert_allclose(rms, [1.0, 1.0])
    np.testing.assert_allclose(torque, [3.0, 0.0])
    np.testing.assert_allclose(relative, [100.0 / 3.0, 100.0])  # a joint without torque: relative to 1 Nm


def test_bounded_solve_meets_the_optimality_conditions_and_keeps_a_feasible_plain_solution():
    rng = np.random.default_rng(1)
    for trial in range(20):
        A = rng.standard_normal((60, 8)) * np.logspace(-2, 2, 8)  # badly scaled columns, as a regressor's
        G, c = A.T @ A, A.T @ rng.standard_normal(60)
        bounded = rng.random(8) < 0.5
        x = solve(G, c, bounded)
        gradient = G @ x - c  # of ½xᵀGx − cᵀx: 0 where free, ≥ 0 where held at the bound
        scale = np.abs(c).max()
        assert np.all(x[bounded] >= 0.0)
        np.testing.assert_allclose(gradient[~bounded], 0.0, atol=1e-9 * scale)
        assert np.all(gradient[bounded] >= -1e-9 * scale)
        np.testing.assert_allclose(gradient[bounded] * x[bounded], 0.0, atol=1e-9 * scale * max(1.0, x.max()))
        plain = np.linalg.solve(G, c)
        if np.all(plain[bounded] >= 0.0):
            np.testing.assert_allclose(x, plain, rtol=1e-10)


def test_a_negative_viscous_friction_is_fitted_at_zero_and_an_offset_keeps_its_sign():
    rng = np.random.default_rng(2)
    N = 500
    qd = np.sin(np.linspace(0, 20, N)) * 2.0
    Y = rng.standard_normal((N, 2))
    blocks = {Term("viscous", 0): qd[:, None], Term("offset", 0): np.ones((N, 1))}
    tau = Y @ [1.0, 2.0] - 0.3 * qd - 0.5 + 0.01 * rng.standard_normal(N)
    data = Dataset(Y, tau, np.arange(N) * 0.01, np.zeros(N, dtype=int), blocks)
    terms = [Term("viscous", 0), Term("offset", 0)]
    fit = least_squares(NormalEquations(data, terms), terms)
    A = np.column_stack([Y, np.ones(N)])  # the model with the viscous coefficient held at its bound 0
    np.testing.assert_allclose(fit.x, np.insert(np.linalg.lstsq(A, tau, rcond=None)[0], 2, 0.0), atol=1e-10)
    assert fit.x[3] < -0.4  # the offset is free to be negative
    np.testing.assert_array_equal(fit.held, [False, False, True, False])  # held at 0: no two-sided std
    free = least_squares(NormalEquations(data, terms[1:]), terms[1:])  # nothing at a bound
    assert not free.held.any()
