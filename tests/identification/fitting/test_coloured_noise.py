"""The sandwich covariance of a least-squares fit with coloured residuals, against the spread of the
estimates over independent noise draws (Monte Carlo: the independent truth)."""

import numpy as np
import pytest
from scipy import signal

from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import least_squares
from excite_cli.identification.fitting.noise import middle, pieces
from excite_cli.identification.fitting.normal import NormalEquations

RATE, SECONDS = 100.0, 120.0


def _columns(time: np.ndarray) -> np.ndarray:
    """(N, 3) slow columns, as a trajectory's (a Fourier series of 0.1 Hz fundamental through the
    regressor's trigonometric functions): gravity-like and inertia-like."""
    q = 0.8 * np.sin(2 * np.pi * 0.1 * time) + 0.4 * np.cos(2 * np.pi * 0.3 * time + 0.5)
    qdd = -0.8 * (2 * np.pi * 0.1) ** 2 * np.sin(2 * np.pi * 0.1 * time) - 0.4 * (2 * np.pi * 0.3) ** 2 * np.cos(
        2 * np.pi * 0.3 * time + 0.5
    )
    return np.column_stack([np.cos(q), np.sin(q), qdd])


def _noise(kind: str, size: int, rng: np.random.Generator) -> np.ndarray:
    """Stationary noise of ``size`` samples (the filter's edges trimmed, as preprocessing trims them)."""
    white = rng.normal(0.0, 1.0, size + 400)
    low_pass = signal.butter(4, 5.0, fs=RATE, output="sos")
    if kind == "white":
        out = white
    elif kind == "low-passed":  # a torque sensor's noise after the 5 Hz parallel filter
        out = signal.sosfiltfilt(low_pass, white)
    else:  # that, and 10 times its variance of encoder noise differentiated twice: near the cut-off
        f, h = signal.sosfreqz(low_pass, worN=4096, fs=RATE)
        gain = np.abs(h) ** 4  # the zero-phase filter's
        scale = np.sqrt(10.0 * gain.sum() / (gain * (2.0 * np.sin(np.pi * f / RATE)) ** 4).sum())
        out = signal.sosfiltfilt(low_pass, white + scale * np.diff(rng.normal(0.0, 1.0, size + 402), 2))
    return 0.05 * out[200 : 200 + size]


def _fit(time, A, tau):
    """The sandwich fit, and the standard deviations of the filter's scalar correction σ² (AᵀA)⁻¹ r,
    r = f_s / (2 f_c) (what excite reported before)."""
    data = Dataset(A, tau, time, np.zeros(time.size, dtype=int), {})
    normal = NormalEquations(data, [])
    plain = least_squares(normal, [])
    sandwich = least_squares(normal, [], None, middle=middle(data, plain.x, [], None, RATE))
    return sandwich, plain.std * np.sqrt(RATE / (2 * 5.0))


@pytest.mark.parametrize("kind", ["white", "low-passed", "with encoder noise"])
def test_the_sandwich_is_the_spread_over_noise_draws(kind):
    time = np.arange(int(SECONDS * RATE)) / RATE
    A, theta, rng = _columns(time), np.array([2.0, 1.0, -0.5]), np.random.default_rng(3)
    estimates, stds, scalar = [], [], []
    for _ in range(200):
        tau = A @ theta + _noise(kind, time.size, rng)
        fit, corrected = _fit(time, A, tau)
        estimates.append(fit.x)
        stds.append(fit.std)
        scalar.append(corrected)
    spread = np.std(estimates, axis=0, ddof=1)  # ±5 % with 200 draws
    np.testing.assert_allclose(np.mean(stds, axis=0), spread, rtol=0.15)
    if kind == "with encoder noise":  # the filter's scalar correction charges noise the motion never sees
        assert np.all(np.mean(scalar, axis=0) > 2 * spread)


def test_stretches_split_at_gaps_and_runs():
    time = np.r_[np.arange(50), np.arange(70, 100), np.arange(100, 120)] / RATE
    run = np.r_[np.zeros(80, dtype=int), np.ones(20, dtype=int)]
    data = Dataset(np.zeros((100, 1)), np.zeros(100), time, run, {})
    assert [p.size for p in pieces(data, RATE)] == [50, 30, 20]
