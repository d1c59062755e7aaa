"""The compiled capsule-pair loops against numpy and SciPy: distances from the closest points of the
segments, the per-pair log-sum-exp of SciPy, and one value whichever loop computes it."""

import numpy as np
from scipy.special import logsumexp

from excite_cli.collision.segments import (
    CapsulePairs,
    pair_aggregates,
    pair_distances,
    pair_jacobian,
    segment_closest_points,
)


def _capsules(seed: int, instants: int = 60, count: int = 5):
    """Segment ends (3, T, C) of capsules moving at random, one of them a sphere, and radii (C,)."""
    rng = np.random.default_rng(seed)
    start = rng.normal(size=(3, instants, count)) * 0.2
    end = start + rng.normal(size=(3, 1, count)) * 0.15
    end[:, :, 2] = start[:, :, 2]  # a sphere: a segment of length 0
    return start, end, rng.uniform(0.01, 0.05, count)


def test_pair_distances_are_those_of_the_closest_points():
    start, end, radii = _capsules(0)
    first, second = np.array([0, 0, 1, 2, 3]), np.array([1, 2, 3, 4, 4])
    d = pair_distances(start, end, CapsulePairs(first, second, radii, np.zeros(first.size), 0.05, 300.0))
    c1, c2 = segment_closest_points(start[..., first], end[..., first], start[..., second], end[..., second])
    np.testing.assert_allclose(d, np.linalg.norm(c2 - c1, axis=0) - radii[first] - radii[second], atol=1e-15)


def test_pair_aggregates_are_scipys_log_sum_exp_over_the_instants():
    start, end, radii = _capsules(1)
    first, second = np.array([0, 1, 2]), np.array([3, 4, 0])
    margins, scale, sharpness = np.array([0.01, 0.02, 0.0]), 0.05, 300.0
    pairs = CapsulePairs(first, second, radii, margins, scale, sharpness)
    g = pair_aggregates(start, end, pairs)
    s = (margins - pair_distances(start, end, pairs)) / scale
    np.testing.assert_allclose(g, logsumexp(sharpness * s, axis=0) / sharpness, rtol=1e-14)
    n, m = 3, 4
    rng = np.random.default_rng(2)
    axes, moments = rng.normal(size=(60, 3, n)), rng.normal(size=(60, 3, n))
    moves = np.array([[1.0, 0.0, -1.0], [0.0, 1.0, 1.0], [-1.0, -1.0, 0.0]])
    same, J = pair_jacobian(start, end, pairs, axes, moments, np.ones(n, bool), moves, rng.normal(size=(60, m)))
    assert np.array_equal(same, g) and J.shape == (3, n, m)  # the Jacobian's loop gives the same values
    assert np.all(J[moves == 0.0] == 0.0) and np.all(np.abs(J[moves != 0.0]).sum(axis=1) > 0.0)
