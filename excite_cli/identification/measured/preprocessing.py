"""Preprocessing of measured runs (scipy.signal): uniform resampling of jittery timestamps, a
zero-phase low-pass of q before differentiating it into q̇ and q̈ (when they are not measured), and
the parallel low-pass and decimation that ``Dataset`` applies to the regressor columns and to τ
alike (Gautier 1997), so filtering never breaks τ = W φ.

The default cut-off is ``CUTOFF_FACTOR`` × the trajectory's bandwidth, the frequency below which
``POWER_FRACTION`` of the power of q lies, taken from a Hann-windowed, detrended spectrum of the runs
that are fitted (a validation run of static postures has no bandwidth; an unwindowed spectrum of a
cropped run leaks its edges' steps to high frequencies: 1.97 Hz instead of 0.53 Hz on the cropped
real Panda runs), and at least ``MIN_CUTOFF``: measured torques carry the friction's switching at
velocity reversals, faster than the trajectory itself, and a slow run's 10 × bandwidth (1.6 Hz) lost
to 5 Hz (issue 10). On the real Panda run cut-offs from 4 to 12 Hz give the same error within about
a point, above 15 Hz joint 1's structural vibration (10–50 Hz in its torque) biases the fit."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterator

import numpy as np
from scipy import signal

from excite_cli.errors import ExciteError
from excite_cli.identification.config import PreprocessingConfig
from excite_cli.identification.measured.measurements import Run

#: Decimated rate [Hz] when ``preprocessing.sample_rate`` is not set (data slower than this keep their rate).
DEFAULT_SAMPLE_RATE = 200.0
#: Default cut-off = this × the frequency below which ``POWER_FRACTION`` of q's power lies ...
CUTOFF_FACTOR = 10.0
POWER_FRACTION = 0.99
#: ... at least this [Hz] ...
MIN_CUTOFF = 5.0
#: ... and at most this fraction of the decimated sample rate.
MAX_CUTOFF_FRACTION = 0.4
#: Samples trimmed at each end: this many periods of the cut-off frequency.
EDGE_PERIODS = 3.0
#: Relative distance below which a rate ratio counts as a half (jitter in a run's mean rate).
STEP_TIE = 1e-3
#: Long signals are filtered in chunks of this many samples, overlapping by this many trims.
CHUNK = 6_000
CHUNK_MARGIN = 3


def bandwidth(q: np.ndarray, rate: float, fraction: float = POWER_FRACTION) -> float:
    """Frequency [Hz] below which ``fraction`` of the power of the (T, n) signals lies, from their
    Hann-windowed periodogram after removing a linear trend (scipy.signal.periodogram)."""
    freqs, power = signal.periodogram(q, fs=rate, window="hann", detrend="linear", axis=0)
    cumulative = np.cumsum(power.sum(axis=1))
    return float(freqs[np.searchsorted(cumulative, fraction * cumulative[-1])])


@dataclass(frozen=True)
class Filter:
    """Zero-phase Butterworth low-pass, edge trimming and decimation of one run.

    Attributes:
        sos: second-order sections; rate: sample rate [Hz]; cutoff [Hz]; trim: samples dropped at
        each end; step: decimation step.
    """

    sos: np.ndarray
    rate: float
    cutoff: float
    trim: int
    step: int

    def low_pass(self, x: np.ndarray) -> np.ndarray:
        """Zero-phase filtered x along time (axis 0), column by column: the filter's padded
        temporaries are one column's, not the whole array's (the same values)."""
        if x.ndim == 1:
            return signal.sosfiltfilt(self.sos, x)
        return np.column_stack([signal.sosfiltfilt(self.sos, column) for column in x.T])

    def decimate(self, x: np.ndarray) -> np.ndarray:
        """Filtered, trimmed and decimated x (axis 0), column by column (only the kept samples are
        held for the whole array)."""
        kept = slice(self.trim, x.shape[0] - self.trim, self.step)
        if x.ndim == 1:
            return self.low_pass(x)[kept].copy()
        return np.column_stack([self.low_pass(column)[kept] for column in x.T])

    def kept(self, length: int) -> int:
        """Number of samples :meth:`decimate` keeps of a signal of ``length`` samples."""
        return len(range(self.trim, length - self.trim, self.step))

    def chunks(
        self, values: Callable[[int, int], np.ndarray], length: int, chunk: int = CHUNK
    ) -> Iterator[tuple[int, np.ndarray]]:
        """:meth:`decimate` of a long signal that is never held whole, in pieces: ``values(lo, hi)``
        gives its samples [lo, hi) (rows along axis 0); yields (k, rows), the kept samples k, k+1, ...
        Each chunk of about ``chunk`` samples is filtered with ``CHUNK_MARGIN`` × ``trim`` samples of
        overlap on each side, where the zero-phase filter's start-up has died out (equal to the
        whole-run filter to ~1e-10 relative on the real Panda run at cut-offs of 2 to 8.6 Hz)."""
        kept = np.arange(self.trim, length - self.trim, self.step)
        margin, size = CHUNK_MARGIN * self.trim, max(1, chunk // self.step)
        for start in range(0, kept.size, size):
            idx = kept[start : start + size]
            lo, hi = max(0, idx[0] - margin), min(length, idx[-1] + margin + 1)
            yield start, signal.sosfiltfilt(self.sos, values(lo, hi), axis=0)[idx - lo]  # a chunk: all columns at once


@dataclass(frozen=True)
class Samples:
    """One run on a uniform grid at its own rate, with q̇ and q̈.

    Attributes:
        name, role: from the run; time: (T,) [s]; q, qd, qdd: per joint, (T,) [rad, rad/s, rad/s²]
        each (a list, so that a joint's signals can be released once they are used);
        tau: (K, n) [Nm] already low-passed and decimated by ``filter`` (the regressor and the
        effect columns get the same filter and decimation later: the parallel filtering);
        filter: the run's filter.
    """

    name: str
    role: str
    time: np.ndarray
    q: list[np.ndarray | None]
    qd: list[np.ndarray | None]
    qdd: list[np.ndarray | None]
    tau: np.ndarray
    filter: Filter

    def states(self, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, q̇, q̈ (hi − lo, n) of the samples [lo, hi)."""
        return tuple(np.column_stack([x[lo:hi] for x in signals]) for signals in (self.q, self.qd, self.qdd))


def run_rate(run: Run) -> float:
    """Mean sample rate of a run [Hz]."""
    return (run.time.size - 1) / (run.time[-1] - run.time[0])


def uniform_grid(run: Run) -> np.ndarray:
    """(T,) uniform instants at the run's mean rate over its span [s]."""
    grid = run.time[0] + np.arange(run.time.size) / run_rate(run)
    return grid[grid <= run.time[-1]]


def resample(run: Run, x: np.ndarray | None, grid: np.ndarray) -> list[np.ndarray] | None:
    """The columns of x (T_run, n) linearly interpolated at ``grid`` (removes timestamp jitter): n
    arrays (T,)."""
    return None if x is None else [np.interp(grid, run.time, column) for column in x.T]


def choose_cutoff(runs: list[Run], cfg: PreprocessingConfig) -> tuple[float, str]:
    """The low-pass cut-off [Hz] of every run and where it came from, in words: ``cfg.cutoff``, or
    ``CUTOFF_FACTOR`` × the largest bandwidth of the fitted runs' resampled q (all runs when none
    is fitted), at least ``MIN_CUTOFF`` and at most ``MAX_CUTOFF_FRACTION`` × the decimated rate."""
    if cfg.cutoff is not None:
        return cfg.cutoff, "preprocessing.cutoff"
    fitted = [r for r in runs if r.role != "validation"] or runs
    widest = max(bandwidth(np.column_stack(resample(r, r.q, uniform_grid(r))), run_rate(r)) for r in fitted)
    top = MAX_CUTOFF_FRACTION * min(target_rate(cfg, run_rate(r)) for r in runs)
    cutoff = float(min(max(MIN_CUTOFF, CUTOFF_FACTOR * widest), top))
    return cutoff, (
        f"default: {CUTOFF_FACTOR:g} × the {100 * POWER_FRACTION:g} % power bandwidth of q in the fitted runs "
        f"({widest:.3g} Hz), at least {MIN_CUTOFF:g} Hz, at most {100 * MAX_CUTOFF_FRACTION:g} % of the rate"
    )


def target_rate(cfg: PreprocessingConfig, rate: float) -> float:
    """The rate [Hz] a run of ``rate`` [Hz] is decimated to: ``preprocessing.sample_rate``, by default
    ``DEFAULT_SAMPLE_RATE``, never above the run's own."""
    return min(DEFAULT_SAMPLE_RATE if cfg.sample_rate is None else cfg.sample_rate, rate)


def decimation_step(rate: float, target: float) -> int:
    """Samples per kept sample: ``rate`` / ``target`` rounded, a half rounded up within
    ``STEP_TIE`` (500 Hz to 200 Hz: 3, for a whole run and for each piece between its gaps alike,
    whose rates differ in the last digits; plain rounding gave 2 or 3 by those digits, and a gap
    seemed to cost 20 % of the rows)."""
    return max(1, int(np.floor(rate / target + 0.5 + STEP_TIE)))


def preprocess(run: Run, cfg: PreprocessingConfig, cutoff: float) -> Samples:
    """Resample one run to a uniform grid, low-pass q (and measured q̇, q̈) and differentiate.

    Args:
        cutoff: low-pass cut-off [Hz] (the same for every run).

    Raises:
        ExciteError: a cut-off at or above the Nyquist frequency of ``sample_rate``, or a run
            shorter than the filter needs.
    """
    rate = run_rate(run)
    grid = uniform_grid(run)
    q, qd, qdd = (resample(run, x, grid) for x in (run.q, run.qd, run.qdd))
    if cfg.sample_rate is not None and cfg.sample_rate > 1.01 * rate:
        raise ExciteError(
            "preprocessing.sample_rate",
            f"{cfg.sample_rate:g} Hz is above the {rate:.4g} Hz of {run.name}; "
            "resampling cannot add information (use at most the data's rate)",
        )
    target = target_rate(cfg, rate)
    if cutoff >= 0.5 * target:
        raise ExciteError(
            "preprocessing.cutoff",
            f"{cutoff:.3g} Hz is not below the Nyquist frequency {0.5 * target:.3g} Hz of "
            f"preprocessing.sample_rate (and of {run.name}); raise sample_rate or lower cutoff",
        )
    sos = signal.butter(cfg.filter_order, cutoff, fs=rate, output="sos")
    trim = int(np.ceil(EDGE_PERIODS * rate / cutoff))
    needed = max(3 * (2 * len(sos) + 1), 2 * trim + 10)
    if grid.size <= needed:
        raise ExciteError(
            "data",
            f"{run.name}: {grid.size} samples ({grid[-1] - grid[0]:.3g} s) are fewer than the "
            f"{needed:.4g} that the {cutoff:.3g} Hz filter needs",
        )
    filt = Filter(sos, rate, cutoff, trim, decimation_step(rate, target))
    dt = 1.0 / rate
    q = [filt.low_pass(c) for c in q]
    qd = [filt.low_pass(c) for c in qd] if qd is not None else [np.gradient(c, dt) for c in q]
    qdd = [filt.low_pass(c) for c in qdd] if qdd is not None else [np.gradient(c, dt) for c in qd]
    tau = np.column_stack([filt.decimate(c) for c in resample(run, run.tau, grid)])  # only its kept samples are held
    return Samples(run.name, run.role, grid, q, qd, qdd, tau, filt)
