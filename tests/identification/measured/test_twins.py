"""Recordings of one motion found by their path in state space: a trajectory recorded again (another
start in its period, more periods, its own noise, stopped early) is one; distinct motions of the same
amplitudes are not."""

import numpy as np
import pytest

from excite_cli.identification.data_config import RunConfig
from excite_cli.identification.measured.twins import motion_print, same_motion, trajectory_groups

RATE, PERIOD = 100.0, 10.0


def fourier(coefficients: np.ndarray, start: float, periods: float, rng, noise: float = 1e-4):
    """The motion print of a 5-harmonic motion of period 10 s recorded from ``start`` [s], ``periods``
    long, with encoder-like noise."""
    t = start + np.arange(int(periods * PERIOD * RATE)) / RATE
    w = 2 * np.pi / PERIOD * np.arange(1, 6)
    a, b = coefficients
    q = np.sin(np.outer(t, w)) @ a.T + np.cos(np.outer(t, w)) @ b.T
    return motion_print(t, q + rng.normal(0.0, noise, q.shape))


@pytest.mark.parametrize("seed", range(10))
def test_a_trajectory_recorded_again_is_one_motion_and_another_motion_is_not(seed):
    rng = np.random.default_rng(seed)
    one, other = (rng.normal(0, 0.3, (2, 7, 5)) / np.arange(1, 6) for _ in range(2))
    first = fourier(one, 0.0, 2.0, rng)
    again = fourier(one, rng.uniform(0, PERIOD), 3.0, rng)  # later in its period, longer
    assert same_motion(first, again)
    assert same_motion(first, fourier(one, 0.0, 0.6, rng))  # a first try stopped at 60 % of the period
    assert same_motion(fourier(one, 2.0, 0.3, rng), first)  # a piece from within, either order
    assert not same_motion(first, fourier(other, 0.0, 2.0, rng))
    assert not same_motion(first, fourier(other, 0.0, 0.6, rng))


@pytest.mark.parametrize("n", [1, 2])
def test_one_or_two_joints_tell_distinct_motions_apart_by_their_velocities(n):
    """A single joint's angles of two motions of one amplitude overlap; their velocities do not."""
    rng = np.random.default_rng(n)
    for _ in range(10):
        one, other = (rng.normal(0, 0.3, (2, n, 5)) / np.arange(1, 6) for _ in range(2))
        assert same_motion(fourier(one, 0.0, 1.0, rng), fourier(one, 4.0, 0.5, rng))
        assert not same_motion(fourier(one, 0.0, 1.0, rng), fourier(other, 0.0, 1.0, rng))


def test_named_runs_keep_their_names_and_unnamed_recordings_of_one_motion_are_one_trajectory(tmp_path):
    rng = np.random.default_rng(0)
    one, other = (rng.normal(0, 0.3, (2, 7, 5)) / np.arange(1, 6) for _ in range(2))
    runs = [RunConfig(file=f"r{k}.csv") for k in range(4)] + [RunConfig(file="r0.csv", crop=(1.0, 5.0))]
    runs.append(RunConfig(file="n.csv", trajectory="named"))
    prints = [fourier(one, 0, 2, rng), fourier(other, 0, 2, rng), fourier(one, 3, 2, rng), fourier(other, 7, 1, rng)]
    prints += [fourier(one, 1, 0.4, rng), fourier(one, 0, 2, rng)]  # a crop of r0; a named recording of r0's motion
    groups, repeats = trajectory_groups(runs, tmp_path, prints)
    assert groups[0] == groups[2] == groups[4] and groups[1] == groups[3] and groups[0] != groups[1]
    assert groups[5] not in groups[:5]  # a name is kept whatever the motion
    assert sorted(repeats) == [(2, 0), (3, 1)]
