"""Weighted least squares on the normal equations kept per joint, against the closed form; friction and
armature kept non-negative, against the optimality conditions of the bounded problem."""

import numpy as np
import scipy.linalg
import scipy.optimize

from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import least_squares, torque_errors
from excite_cli.identification.fitting.normal import NormalEquations, solve, weighted_fit


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


def test_a_fit_weighed_sample_by_sample_is_the_closed_form_of_generalized_least_squares():
    """Each instant's row of each joint scaled by its own weight (an effect block on one joint, a
    coupled one on two): the closed form of the scaled rows."""
    rng = np.random.default_rng(3)
    N, n, b = 300, 2, 3
    Y = rng.standard_normal((N * n, b))
    blocks = {Term("offset", 0): np.ones((N, 1)), Term("offset", 0, coupling=(1.0, -1.0)): rng.standard_normal((N, 1))}
    terms = list(blocks)
    tau = rng.standard_normal(N * n)
    scale = rng.uniform(0.1, 10.0, (N, n))
    x = weighted_fit(Dataset(Y, tau, np.arange(N) * 0.01, np.zeros(N, dtype=int), blocks), terms, scale)
    offset = np.zeros(N * n)
    offset[0::n] = 1.0
    motor = np.zeros(N * n)
    motor[0::n], motor[1::n] = blocks[terms[1]][:, 0], -blocks[terms[1]][:, 0]
    A = np.column_stack([Y, offset, motor]) * scale.ravel()[:, None]
    np.testing.assert_allclose(x, np.linalg.lstsq(A, tau * scale.ravel(), rcond=None)[0], rtol=1e-9, atol=1e-12)


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


def test_a_dependent_column_gets_the_minimum_norm_solution_whether_or_not_cholesky_accepts_it():
    """A column the others span exactly: by rounding, Cholesky accepts half of these systems (its last
    pivot is ~1e-16); the solution must be the minimum-norm least squares of the unit-diagonal columns
    (numpy's SVD lstsq) on every one, not the huge coefficients of a rounding pivot."""
    accepted = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        X = rng.standard_normal((50, 3)) * [1.0, 3.0, 0.2]
        X = np.column_stack([X, 0.7 * X[:, 0] + 1.3 * X[:, 1]])
        y = X @ [1.0, -2.0, 0.5, 0.0] + 0.1 * rng.standard_normal(50)
        G = X.T @ X
        d = np.sqrt(np.diag(G))
        try:
            scipy.linalg.cho_factor(G / np.outer(d, d))
            accepted += 1
        except np.linalg.LinAlgError:
            pass
        expected = np.linalg.lstsq(X / d, y, rcond=None)[0] / d
        np.testing.assert_allclose(solve(G, X.T @ y), expected, rtol=1e-6, atol=1e-9)
    assert accepted >= 5  # the case the rule exists for is among them


def test_dependent_columns_kept_non_negative_do_not_follow_the_rounding():
    """Columns kept ≥ 0 (friction, armature): one the free columns span exactly, one independent, one
    the data never see (a zero column), the unconstrained solution negative on the first two. The
    bounded solve eliminates the free columns; the Schur complement of the first and the last is
    rounding. The solution must not move when G moves by 1e-15 of its scale (as the order of a sum
    moves it with the number of BLAS threads), must stay near the data's coefficients, and must fit as
    well as scipy's bounded least squares of the columns that add to the fit."""
    for seed in range(20):
        rng = np.random.default_rng(seed)
        X = rng.standard_normal((50, 3)) * [1.0, 3.0, 0.2]
        X = np.column_stack([X, 0.7 * X[:, 0] + 1.3 * X[:, 1], rng.standard_normal(50), np.zeros(50)])
        y = X[:, :3] @ [-1.0, -2.0, 0.5] - 0.3 * X[:, 4] + 0.1 * rng.standard_normal(50)
        G, c = X.T @ X, X.T @ y
        rounding = rng.standard_normal(G.shape)
        rounding = (rounding + rounding.T) * 1e-15 * np.sqrt(np.outer(np.diag(G), np.diag(G)))
        kept = np.array([False, False, False, True, True, True])
        x = solve(G, c, kept)
        np.testing.assert_allclose(solve(G + rounding, c, kept), x, atol=1e-9)
        assert np.all(x[kept] >= 0.0) and np.abs(x).max() < 10.0
        own = [0, 1, 2, 4]  # the columns that add to the fit: scipy's bounded least squares on them
        best = scipy.optimize.lsq_linear(X[:, own], y, bounds=([-np.inf] * 3 + [0.0], np.inf), tol=1e-12).x
        np.testing.assert_allclose(np.sum((X @ x - y) ** 2), np.sum((X[:, own] @ best - y) ** 2), rtol=1e-7)
