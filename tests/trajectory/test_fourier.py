"""Fourier series (Eq. 50): derivatives and the chain rule (Eq. 49) against finite differences."""

import numpy as np
import pytest

from excite_cli.trajectory.fourier import FourierTrajectory, sample_times


def test_velocity_and_acceleration_match_time_differences():
    traj = FourierTrajectory(harmonics=5, base_frequency=0.9)
    alpha = np.random.default_rng(0).normal(size=(3, traj.n_coefficients))
    t = np.linspace(0.0, 7.0, 50)
    h = 1e-5
    q_plus, qd_plus, _ = traj.basis(t + h).evaluate(alpha)
    q_minus, qd_minus, _ = traj.basis(t - h).evaluate(alpha)
    _, qd, qdd = traj.basis(t).evaluate(alpha)
    np.testing.assert_allclose(qd, (q_plus - q_minus) / (2 * h), rtol=1e-7, atol=1e-7)
    np.testing.assert_allclose(qdd, (qd_plus - qd_minus) / (2 * h), rtol=1e-7, atol=1e-6)


def test_closed_form_single_harmonic():
    traj = FourierTrajectory(harmonics=2, base_frequency=2.0)
    alpha = np.array([[0.3, 0.0, 0.5, 0.0, 0.0]])  # q = 0.3 + 0.5 sin(4t)
    t = np.array([0.1, 0.7])
    q, qd, qdd = traj.basis(t).evaluate(alpha)
    np.testing.assert_allclose(q[:, 0], 0.3 + 0.5 * np.sin(4 * t))
    np.testing.assert_allclose(qd[:, 0], 2.0 * np.cos(4 * t))
    np.testing.assert_allclose(qdd[:, 0], -8.0 * np.sin(4 * t))


def test_chain_rule_matches_finite_differences():
    traj = FourierTrajectory(harmonics=3, base_frequency=1.1)
    basis = traj.basis(np.linspace(0, 5, 20))
    rng = np.random.default_rng(1)
    alpha = rng.normal(size=(2, traj.n_coefficients))
    weights = [rng.normal(size=(20, 2)) for _ in range(3)]

    def f(a):
        return sum(float(np.sum(w * x)) for w, x in zip(weights, basis.evaluate(a)))

    grad = basis.chain(*weights)
    fd = np.zeros_like(alpha)
    for i in np.ndindex(alpha.shape):
        e = np.zeros_like(alpha)
        e[i] = 1e-6
        fd[i] = (f(alpha + e) - f(alpha - e)) / 2e-6
    np.testing.assert_allclose(grad, fd, rtol=1e-6, atol=1e-6)


def test_sample_times_match_the_paper_grids():
    assert sample_times(8.0, 0.2).size == 40
    assert sample_times(8.0, 0.02, include_end=True).size == 401
    np.testing.assert_allclose(sample_times(8.0, 0.2)[-1], 7.8)


def test_nyquist_rate_is_twice_the_highest_harmonic_and_below_it_samples_alias():
    trajectory = FourierTrajectory(harmonics=3, base_frequency=2 * np.pi * 0.5)  # harmonics at 0.5, 1, 1.5 Hz
    assert trajectory.nyquist_rate == pytest.approx(3.0)
    # at 2.5 Hz the 1.5 Hz harmonic's samples are those of a 1.0 Hz sine (aliasing): the motion is lost
    t = np.arange(10) / 2.5
    assert np.allclose(np.sin(2 * np.pi * 1.5 * t), -np.sin(2 * np.pi * 1.0 * t))
