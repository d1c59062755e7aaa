"""The correlation of two sampled motions against closed forms: a motion with itself 1, with its
mirror −1, sinusoids of different harmonics 0 over whole periods, and with cos(φ) for a phase φ."""

import numpy as np
import pytest

from excite_cli.trajectory.similarity import correlation

T = np.linspace(0.0, 10.0, 1000, endpoint=False)  # whole periods of ω = 2π/10


def _motion(harmonic: int, phase: float = 0.0, offset: float = 0.3) -> np.ndarray:
    w = 2 * np.pi / 10.0 * harmonic
    return np.stack([offset + np.sin(w * T + phase), -offset + 0.5 * np.sin(w * T + phase)], axis=1)


def test_correlations_of_closed_forms():
    q = _motion(1)
    assert correlation(q, q) == pytest.approx(1.0)
    assert correlation(q, 3.0 * _motion(1, offset=2.0)) == pytest.approx(1.0)  # amplitude and offset do not count
    assert correlation(q, -q) == pytest.approx(-1.0)
    assert correlation(q, _motion(2)) == pytest.approx(0.0, abs=1e-12)
    assert correlation(q, _motion(1, phase=np.pi / 3)) == pytest.approx(np.cos(np.pi / 3))


def test_a_motion_standing_still_correlates_with_nothing_and_shapes_must_match():
    assert correlation(_motion(1), np.ones((1000, 2))) == 0.0
    with pytest.raises(ValueError, match="shapes"):
        correlation(_motion(1), _motion(1)[:, :1])
