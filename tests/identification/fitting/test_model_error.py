"""The spread between trajectories against its own truth (bench/model_error.py's analogue): a Panda
whose joint 2 has a spring the model lacks, recorded on many distinct random trajectories. Sets of 4
trajectories (disjoint) are fitted by least squares: the spread of their estimates over the sets is
what the reported standard deviation of one set must predict; the noise-only one does not. Two
recordings of one trajectory count as one trajectory: counted as two, the spread is underestimated.
One recording (bench/recording_halves.py's analogue): the spread between its halves, each fitted on its
own, is what the time blocks' std of a half predicts; the noise's sandwich underestimates it."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "bench"))

import model_error as analogue  # noqa: E402  (bench/model_error.py)
import recording_halves as halves  # noqa: E402  (bench/recording_halves.py)

from excite_cli.identification.fitting.least_squares import least_squares  # noqa: E402
from excite_cli.identification.fitting.model_error import between_trajectories  # noqa: E402
from excite_cli.identification.fitting.normal import NormalEquations  # noqa: E402

#: Disjoint sets of trajectories.
SETS = 30


@pytest.fixture(scope="module")
def panda():
    return analogue.panda()


def _fit(robot, base, recordings, trajectory):
    """Least squares of the recordings pooled: estimates, noise-only and reported std of the base parameters."""
    data, terms = analogue.pooled(robot, recordings)
    fit = least_squares(NormalEquations(data, terms), terms)
    between = np.sqrt(between_trajectories(data, fit.x, terms, None, np.asarray(trajectory)))
    return fit.x[: base.count], fit.std[: base.count], between[: base.count]


def _ratios(estimates, stds):
    """Per base parameter the data determine: the RMS of the std over the sets / the estimates' spread."""
    x = np.array(estimates)
    spread = x.std(axis=0, ddof=1)
    resolved = spread > 1e-6 * np.abs(x).mean(axis=0)
    return np.sqrt((np.array(stds) ** 2).mean(axis=0))[resolved] / spread[resolved]


def test_the_spread_between_trajectories_is_what_the_reported_std_predicts(panda):
    robot, base = panda
    rng = np.random.default_rng(0)
    fits = []
    for _ in range(SETS):
        recordings = [analogue.recording(robot, base, analogue.motion(rng, robot.n_joints), rng) for _ in range(4)]
        fits.append(_fit(robot, base, recordings, np.arange(4)))
    x, noise_only, between = zip(*fits)
    ratio = _ratios(x, between)
    assert np.mean((ratio > 0.7) & (ratio < 1.4)) >= 0.8, np.round(ratio, 2)
    assert np.median(_ratios(x, noise_only)) < 0.5  # the model error is not noise


def test_two_recordings_of_one_trajectory_are_one_trajectory(panda):
    """4 trajectories recorded twice each: clustered by trajectory the std matches the spread over
    sets; clustered by recording (8) it is smaller (the twins share their model error)."""
    robot, base = panda
    rng = np.random.default_rng(1)
    estimates, by_trajectory, by_recording = [], [], []
    for _ in range(SETS):
        motions = [analogue.motion(rng, robot.n_joints) for _ in range(4)]
        recordings = [analogue.recording(robot, base, m, rng) for m in motions for _ in range(2)]
        x, _, between = _fit(robot, base, recordings, np.repeat(np.arange(4), 2))
        estimates.append(x)
        by_trajectory.append(between)
        by_recording.append(_fit(robot, base, recordings, np.arange(8))[2])
    right, apart = _ratios(estimates, by_trajectory), _ratios(estimates, by_recording)
    assert np.mean((right > 0.7) & (right < 1.4)) >= 0.8, np.round(right, 2)
    assert np.median(apart) < 0.9 * np.median(right)


def test_the_spread_between_halves_of_a_recording_is_what_the_time_blocks_predict(panda):
    """Halves of recordings of a non-repeating motion with a spring the model lacks, each fitted on
    its own: the RMS of the time blocks' std of the halves' difference over the RMS of the difference,
    median over the base parameters, within 0.7–1.4 (the sandwich's is lower: the model error grows
    with the regressor's rows, which a noise spectrum cannot hold)."""
    robot, base = panda
    rng, b = np.random.default_rng(0), base.count
    pairs = []
    for _ in range(60):
        t, Y, tau, qd = halves.recording(robot, base, rng, "spring", halves.LENGTH)
        pairs.append([halves.half(t, Y, tau, qd, rows) for rows in np.array_split(np.arange(t.size), 2)])
    spread = np.sqrt(np.mean([(p[0][0] - p[1][0])[:b] ** 2 for p in pairs], axis=0))
    ratio = {k: np.sqrt(np.mean([(p[0][k] ** 2 + p[1][k] ** 2)[:b] for p in pairs], axis=0)) / spread for k in (1, 2)}
    assert 0.7 < np.median(ratio[2]) < 1.4 and np.mean((ratio[2] > 0.7) & (ratio[2] < 1.4)) >= 0.8, ratio[2]
    assert np.median(ratio[1]) < np.median(ratio[2]) - 0.05
