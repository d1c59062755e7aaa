"""Preprocessing of measured runs (scipy.signal): uniform resampling of jittery timestamps, zero-phase
low-pass filtering of q and τ alike, q̇ and q̈ by differentiation when not measured, edge trimming and
decimation. The default cut-off is ``CUTOFF_FACTOR`` × the trajectory's bandwidth, estimated from the
spectrum of q."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

from excite_cli.config import PreprocessingConfig
from excite_cli.errors import ExciteError
from excite_cli.identification.measurements import Run

#: Default cut-off = this × the frequency below which 99.9 % of q's power lies.
CUTOFF_FACTOR = 5.0
#: Samples trimmed at each end: this many periods of the cut-off frequency.
EDGE_PERIODS = 3.0


@dataclass(frozen=True)
class Samples:
    """Preprocessed samples of one run on a uniform grid.

    Attributes:
        name: run name; role: ``fit``, ``validation`` or ``blocks``.
        time: (T,) [s]; q, qd, qdd, tau: (T, n) [rad, rad/s, rad/s², Nm].
        cutoff: the low-pass cut-off used [Hz].
    """

    name: str
    role: str
    time: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    cutoff: float

    def select(self, mask: np.ndarray, role: str) -> "Samples":
        """The samples where ``mask`` (T,) is true, with another role."""
        return Samples(self.name, role, self.time[mask], self.q[mask], self.qd[mask], self.qdd[mask], self.tau[mask], self.cutoff)


def bandwidth(q: np.ndarray, rate: float, fraction: float = 0.999) -> float:
    """Frequency [Hz] below which ``fraction`` of the power of the detrended (T, n) signals lies."""
    power = np.abs(np.fft.rfft(signal.detrend(q, axis=0), axis=0)) ** 2
    cumulative = np.cumsum(power.sum(axis=1))
    freqs = np.fft.rfftfreq(q.shape[0], 1.0 / rate)
    return float(freqs[np.searchsorted(cumulative, fraction * cumulative[-1])])


def preprocess(run: Run, cfg: PreprocessingConfig) -> Samples:
    """Resample, filter, differentiate, trim and decimate one run.

    Raises:
        ExciteError: a cut-off at or above the decimated rate's Nyquist frequency, or a run shorter
            than the filter needs.
    """
    rate = (run.time.size - 1) / (run.time[-1] - run.time[0])
    grid = run.time[0] + np.arange(run.time.size) / rate
    grid = grid[grid <= run.time[-1]]

    def resample(x: np.ndarray | None) -> np.ndarray | None:
        return None if x is None else np.column_stack([np.interp(grid, run.time, x[:, j]) for j in range(x.shape[1])])

    q, qd, qdd, tau = (resample(x) for x in (run.q, run.qd, run.qdd, run.tau))
    target = min(cfg.sample_rate, rate)
    cutoff = cfg.cutoff or max(CUTOFF_FACTOR * bandwidth(q, rate), 0.5)
    if cutoff >= 0.5 * target:
        raise ExciteError(
            f"preprocessing.cutoff: {cutoff:.3g} Hz is not below the Nyquist frequency {0.5 * target:.3g} Hz of "
            f"preprocessing.sample_rate; raise sample_rate or lower cutoff"
        )
    sos = signal.butter(cfg.filter_order, cutoff, fs=rate, output="sos")
    trim = int(np.ceil(EDGE_PERIODS * rate / cutoff))
    needed = max(3 * (2 * len(sos) + 1), 2 * trim + 10)
    if grid.size <= needed:
        raise ExciteError(
            f"data: {run.name}: {grid.size} samples ({grid[-1] - grid[0]:.3g} s) are fewer than the "
            f"{needed} the {cutoff:.3g} Hz filter needs"
        )
    dt = 1.0 / rate

    def smooth(x: np.ndarray) -> np.ndarray:
        return signal.sosfiltfilt(sos, x, axis=0)

    q = smooth(q)
    qd = smooth(qd) if qd is not None else np.gradient(q, dt, axis=0)
    qdd = smooth(qdd) if qdd is not None else np.gradient(qd, dt, axis=0)
    tau = smooth(tau)
    step = max(1, int(round(rate / target)))
    keep = slice(trim, grid.size - trim, step)
    return Samples(run.name, run.role, grid[keep], q[keep], qd[keep], qdd[keep], tau[keep], cutoff)
