"""Fourier-series joint trajectories (Eq. 50) and their constant Jacobians in α (Eqs. 48–49).

For joint j, q_j(t) = q0_j + Σ_{k=1..N} a_{j,k} sin(kωt) + b_{j,k} cos(kωt).
The Fourier coefficients of one joint are stored as the row α_j = [q0_j, a_{j,1..N}, b_{j,1..N}],
so α is an (n_joints, 2N+1) array. q, q̇ and q̈ are linear in α: x_d(t) = B_d(t) α_jᵀ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FourierBasis:
    """Fourier basis sampled at T instants.

    Attributes:
        time: (T,) instants [s].
        q, qd, qdd: (T, 2N+1) rows B(t) such that q(t) = B_q(t) α_jᵀ [rad], q̇ [rad/s], q̈ [rad/s²].
    """

    time: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(T, n) arrays q [rad], q̇ [rad/s], q̈ [rad/s²] of the coefficients α (n, 2N+1)."""
        return self.q @ alpha.T, self.qd @ alpha.T, self.qdd @ alpha.T

    def chain(self, dq: np.ndarray, dqd: np.ndarray, dqdd: np.ndarray) -> np.ndarray:
        """Gradient in α (n, 2N+1) of a scalar whose gradients in the (T, n) samples are given (Eq. 49)."""
        return dq.T @ self.q + dqd.T @ self.qd + dqdd.T @ self.qdd


@dataclass(frozen=True)
class FourierTrajectory:
    """Fourier series with N harmonics of the base frequency ω [rad/s] (Eq. 50)."""

    harmonics: int
    base_frequency: float

    @property
    def n_coefficients(self) -> int:
        """Coefficients per joint, 2N+1."""
        return 2 * self.harmonics + 1

    @property
    def period(self) -> float:
        """Period 2π/ω [s]."""
        return 2.0 * np.pi / self.base_frequency

    @property
    def nyquist_rate(self) -> float:
        """Twice the highest harmonic's frequency, N ω / π [Hz]: a sample rate at or below it cannot
        represent the motion (Shannon)."""
        return self.harmonics * self.base_frequency / np.pi

    def basis(self, time: np.ndarray) -> FourierBasis:
        """The basis at the instants ``time`` (T,) [s]."""
        time = np.asarray(time, dtype=float)
        k = np.arange(1, self.harmonics + 1)
        w = k * self.base_frequency
        phase = np.outer(time, w)
        s, c = np.sin(phase), np.cos(phase)
        ones, zeros = np.ones((time.size, 1)), np.zeros((time.size, 1))
        return FourierBasis(
            time=time,
            q=np.hstack([ones, s, c]),
            qd=np.hstack([zeros, w * c, -w * s]),
            qdd=np.hstack([zeros, -(w**2) * s, -(w**2) * c]),
        )


def sample_times(duration: float, period: float, include_end: bool = False) -> np.ndarray:
    """Instants 0, period, 2·period, ... below ``duration`` [s] (up to it if ``include_end``)."""
    count = int(np.floor(duration / period + 1e-9)) + (1 if include_end else 0)
    return np.arange(count) * period
