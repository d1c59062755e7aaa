"""What every constraint shares: acceptance by all of them, the bisection towards the farthest
accepted point, and the log-sum-exp aggregation's bounds."""

import numpy as np
import pytest
from scipy.special import logsumexp, softmax

from excite_cli.constraints.constraint import Constraint, FineCheck, accepted, farthest_accepted
from excite_cli.constraints.lse import ACCEPT_MARGIN, GRID_MARGIN, SHARPNESS, smooth_max, smooth_max_value


class Ball(Constraint):
    """|α| ≤ radius, a constraint whose boundary is known."""

    name, field, grid_margin = "ball", "test.ball", 0.0

    def __init__(self, radius: float):
        self.radius, self.basis = radius, None

    def evaluate(self, alpha):
        return np.array([np.linalg.norm(alpha) - self.radius]), (alpha / np.linalg.norm(alpha)).reshape(1, -1)

    def check_samples(self, time, q, qd, qdd):  # pragma: no cover - the tests use check() below
        raise NotImplementedError

    def check(self, alpha, basis):
        return FineCheck(float(np.linalg.norm(alpha) - self.radius), {})


def test_farthest_accepted_point_is_the_boundary_of_the_tightest_constraint():
    start, end = np.zeros((1, 2)), np.array([[3.0, 4.0]])  # |end| = 5
    constraints = [Ball(2.0), Ball(4.0)]
    assert accepted(constraints, start) and not accepted(constraints, end)
    t = farthest_accepted(constraints, start, end, steps=30)
    assert t == pytest.approx(2.0 / 5.0, abs=1e-8) and accepted(constraints, start + t * (end - start))
    assert farthest_accepted([Ball(10.0)], start, end, steps=5) == pytest.approx(1 - 2**-5)  # all of it accepted


def test_smooth_max_never_underestimates_and_overshoots_by_at_most_log_count_over_beta():
    values = np.random.default_rng(0).uniform(-0.5, 0.1, (50, 3))
    g, weights = smooth_max(values, axis=0)
    assert np.all(g >= values.max(axis=0) + GRID_MARGIN - 1e-15)
    assert np.all(g <= values.max(axis=0) + GRID_MARGIN + np.log(50) / SHARPNESS)
    np.testing.assert_allclose(weights.sum(axis=0), 1.0)
    assert np.array_equal(smooth_max_value(values, axis=0), g)  # the values-only path gives the same g
    assert ACCEPT_MARGIN == GRID_MARGIN / 2


def test_smooth_max_is_scipys_log_sum_exp_and_softmax_over_any_axes():
    values = np.random.default_rng(1).uniform(-3.0, 0.2, (2, 40, 5))
    for axis in (1, (0, 1)):
        g, weights = smooth_max(values, axis=axis)
        np.testing.assert_allclose(g, logsumexp(SHARPNESS * values, axis=axis) / SHARPNESS + GRID_MARGIN, rtol=1e-14)
        np.testing.assert_allclose(weights, softmax(SHARPNESS * values, axis=axis), rtol=1e-12, atol=1e-300)
    nothing = np.full((4, 2), -np.inf)  # no sample at all: no constraint, and no NaN
    assert np.all(smooth_max_value(nothing, axis=0) == -np.inf)
