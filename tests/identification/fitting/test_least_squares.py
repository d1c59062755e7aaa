"""Weighted least squares on the normal equations kept per joint, against the closed form."""

import numpy as np

from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import least_squares, torque_errors
from excite_cli.identification.fitting.normal import NormalEquations


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
