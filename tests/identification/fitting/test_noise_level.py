"""The noise level σ² = a² + (ρτ)² fitted to a residual: recovered from residuals drawn with known a
and ρ, the right kind preferred, the jackknife's std against the spread over draws, and the filter's
noise gain against white noise passed through it."""

import numpy as np
import pytest
from scipy import signal

from excite_cli.identification.fitting.noise_level import fit_noise_level, measured_noise, noise_gain

RATE = 200.0
TIME = np.arange(0.0, 40.0, 1.0 / RATE)
TORQUE = 8.0 * np.sin(2 * np.pi * 0.2 * TIME) + 3.0 * np.sin(2 * np.pi * 0.55 * TIME + 1.0)  # [Nm]


def _residual(seed: int, a: float, rho: float, sos=None) -> np.ndarray:
    white = np.random.default_rng(seed).normal(size=TIME.size) * np.sqrt(a**2 + (rho * TORQUE) ** 2)
    return white if sos is None else signal.sosfiltfilt(sos, white)


@pytest.mark.parametrize("a, rho, kind", [(0.1, 0.0, "absolute"), (0.01, 0.02, "relative"), (0.0, 0.05, "relative")])
def test_a_and_rho_are_recovered_and_the_right_kind_preferred_in_nine_of_ten_draws(a, rho, kind):
    levels = [fit_noise_level(_residual(seed, a, rho), TORQUE, np.ones(TIME.size)) for seed in range(10)]
    assert sum(level.preferred == kind for level in levels) >= 9
    fitted = np.array([(level.absolute, level.relative) for level in levels])
    if rho:
        np.testing.assert_allclose(np.median(fitted[:, 1]), rho, rtol=0.05)
    if a:
        np.testing.assert_allclose(np.median(fitted[:, 0]), a, rtol=0.1)


def test_the_jackknife_std_follows_the_spread_over_draws():
    levels = [fit_noise_level(_residual(seed, 0.05, 0.02), TORQUE, np.ones(TIME.size)) for seed in range(40)]
    rho, std = np.array([level.relative for level in levels]), np.array([level.relative_std for level in levels])
    assert 0.6 < np.median(std) / rho.std() < 1.6


def test_the_noise_gain_is_the_variance_white_noise_keeps_through_the_zero_phase_filter():
    sos = signal.butter(4, 10.0, fs=RATE, output="sos")
    white = np.random.default_rng(0).normal(size=400_000)
    np.testing.assert_allclose(noise_gain(sos), signal.sosfiltfilt(sos, white).var(), rtol=0.02)


def test_a_filtered_residual_divided_by_its_gain_gives_the_recordings_own_noise():
    sos = signal.butter(4, 10.0, fs=RATE, output="sos")
    gain = np.full(TIME.size, noise_gain(sos))
    levels = [fit_noise_level(_residual(seed, 0.02, 0.02, sos), TORQUE, gain) for seed in range(10)]
    np.testing.assert_allclose(np.median([level.relative for level in levels]), 0.02, rtol=0.1)
    assert sum(level.preferred == "relative" for level in levels) >= 9


def test_too_short_a_residual_is_refused():
    with pytest.raises(ValueError, match="the jackknife needs at least 20"):
        fit_noise_level(np.zeros(19), np.zeros(19), np.ones(19))


LOADED = 12.0 + 8.0 * np.sin(2 * np.pi * 0.2 * TIME) * np.cos(2 * np.pi * 0.55 * TIME)  # [Nm], never near 0


@pytest.mark.parametrize("a, rho", [(0.02, 0.02), (0.3, 0.002)])
def test_the_upper_bound_of_a_holds_the_true_a_in_eighteen_of_twenty_draws(a, rho):
    """A joint under load whose noise grows with the torque leaves a poorly determined (fitted 0 in some
    draws): its 95 % upper bound is above the true a in ≥ 18 of 20 draws; where the absolute part
    dominates, the bound is within 10 % of a (median)."""
    draws = [np.random.default_rng(seed).normal(size=TIME.size) for seed in range(20)]
    levels = [fit_noise_level(d * np.sqrt(a**2 + (rho * LOADED) ** 2), LOADED, np.ones(TIME.size)) for d in draws]
    upper = np.array([level.absolute_upper for level in levels])
    assert all(level.absolute_upper >= level.absolute for level in levels)
    assert np.sum(upper >= a) >= 18
    if rho * LOADED.mean() < a:
        assert np.median(upper) < 1.1 * a
    else:
        assert min(level.absolute for level in levels) < 0.5 * a  # the fitted a alone falls far below the truth


def test_a_loaded_joint_whose_noise_grows_with_the_torque_reads_its_floor_after_the_reweighted_fits():
    """A model fitted with every sample alike lets the noise of the large-torque samples (2 % of up to
    500 Nm) into its estimates and so into the residual of the small-torque ones, where it reads as a
    floor of 10-25 × the true 0.01 Nm; measured again after the fits reweighted by the noise measured
    (generalized least squares), the fitted a's median is within 0.6-1.6 × the truth, its upper bound
    (what a design takes) within 0.5-3.5 × in every draw, and ρ within 5 %."""
    t = np.arange(4000) / RATE
    Y = np.column_stack([np.sin(2 * np.pi * 0.1 * k * t + k) for k in range(1, 13)])  # (T, 12)
    beta = np.random.default_rng(99).normal(size=12)
    beta *= 500.0 / np.abs(Y @ beta).max()
    tau, a, rho = Y @ beta, 0.01, 0.02
    once, twice = [], []
    for seed in range(10):
        measured = tau + np.random.default_rng(seed).normal(size=tau.size) * np.sqrt(a**2 + (rho * tau) ** 2)

        def fit(w: np.ndarray) -> np.ndarray:
            w = w.ravel()
            return (Y @ np.linalg.lstsq(Y * w[:, None], measured * w, rcond=None)[0])[:, None]

        predicted, gain = fit(np.ones(tau.size)), np.ones(tau.size)
        once.append(fit_noise_level(measured - predicted[:, 0], predicted[:, 0], gain))
        twice.append(measured_noise(measured[:, None], predicted, gain, np.array([True]), fit)[0])
    assert min(level.absolute for level in once) > 10 * a
    fitted, upper = (np.array([getattr(x, f) for x in twice]) for f in ("absolute", "absolute_upper"))
    assert 0.6 * a < np.median(fitted) < 1.6 * a and np.all((0.5 * a < upper) & (upper < 3.5 * a))
    np.testing.assert_allclose([level.relative for level in twice], rho, rtol=0.05)


def test_absolute_noise_is_measured_once():
    """Where no joint's noise grows with the torque, the model is not refitted."""
    predicted = np.column_stack([TORQUE, TORQUE])
    measured = predicted + np.random.default_rng(0).normal(size=predicted.shape) * 0.1
    levels = measured_noise(measured, predicted, np.ones(TIME.size), np.array([True, False]), None)
    assert levels[1] is None and levels[0].preferred == "absolute"


def _deviance(r: np.ndarray, tau: np.ndarray, a2: float, rho2: float) -> float:
    variance = a2 + rho2 * tau**2
    return float(np.sum(np.log(variance) + r**2 / variance))


def test_the_bound_of_a_is_found_where_the_fitted_rho_lies_beyond_the_torques_typical_share():
    """Noise growing as √|τ| at small torques (dry friction's shape) and 1 % of the samples at large
    torques the model follows (a joint pressed against a contact): the fit's ρ² exceeds 10 × r's mean
    over τ's, where the profile of a once ended (a traceback). a's upper bound is the profile
    likelihood's: ρ re-fitted at it, the deviance is 2.706 (χ²₁ at 90 %, one-sided 95 %) above the best."""
    for seed in range(5):
        rng = np.random.default_rng(seed)
        small, large = 0.07 * rng.normal(size=2700), rng.choice([-1.0, 1.0], 30) * rng.uniform(5.0, 9.0, 30)
        tau = np.r_[small, large]
        r = np.r_[np.sqrt(5e-4 + 0.05 * np.abs(small)), 0.1 * np.abs(large)] * rng.normal(size=tau.size)
        level = fit_noise_level(r, tau, np.ones(tau.size))
        assert level.absolute_upper > level.absolute > 0.0
        grid = np.geomspace(1e-6, 1e3, 4001)  # ρ² re-fitted on a wide grid, independent of the fit's search
        best = min(_deviance(r, tau, level.absolute**2, x) for x in grid)
        at_bound = min(_deviance(r, tau, level.absolute_upper**2, x) for x in grid)
        assert at_bound - best == pytest.approx(2.706, abs=0.05)
