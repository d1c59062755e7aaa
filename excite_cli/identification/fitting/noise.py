"""The covariance of a least-squares fit whose residuals are not white: the sandwich
(AᵀWA)⁻¹ (AᵀW Σ W A) (AᵀWA)⁻¹ with Σ from the residuals' own spectra.

σ² (AᵀA)⁻¹ holds for white residuals. The fit data are low-passed and decimated (parallel
filtering), so their residuals are correlated, and their spectrum need not be flat either: a torque
sensor's noise is flat up to the cut-off, but encoder noise differentiated twice into q̈ rises as f⁴
and sits near the cut-off, far from the motion. Modelling each joint's residual e_j as stationary
with power spectral density S_j(f), its covariance is (nearly) circulant on a stretch of L samples,
diagonal in the discrete Fourier basis with eigenvalues f_s S_j(f_l), so for that stretch's rows
A_j of joint j

    A_jᵀ Σ_j A_j ≈ (1/L) Σ_l Â_j(f_l)ᴴ f_s S_j(f_l) Â_j(f_l),   Â_j the DFT of A_j's columns,

summed over the joints (times w_j⁴: W = w_j² on joint j's rows, on each side of Σ) and the data's
contiguous stretches (Pintelon & Schoukens, "System Identification: A Frequency Domain Approach",
2nd ed. 2012, ch. 7: the covariance of a least-squares estimate under coloured noise). S_j is
Welch's estimate from the fit's own residuals. White residuals give σ² (AᵀA)⁻¹ back; residuals
flat up to a low-pass at f_c give the scalar correction r = f_s / (2 f_c) for columns inside the
band; noise outside the motion's band costs the parameters nothing, which the scalar correction
charged in full (a simulated Panda with encoder noise: the reported standard deviations were 2.1 ×
the spread over noise draws).
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import predict

#: Length [s] of the Welch segments: frequency resolution 0.1 Hz, finer than a 10 s trajectory
#: period's fundamental (shorter stretches of data give a coarser one).
SEGMENT = 10.0
#: Stretches shorter than this many samples are left out of the spectra and the sandwich.
SHORTEST = 8
#: Longer stretches enter the sandwich in pieces of this many samples (memory; each piece is still
#: far longer than the residuals' correlation).
LONGEST = 1 << 16


def pieces(data: Dataset, rate: float) -> list[np.ndarray]:
    """Index arrays of the contiguous stretches of ``data``'s instants: one run, no gap of more than
    1.5 sample periods (a run fitted in time blocks is several), each at most ``LONGEST`` long."""
    gap = (np.diff(data.time) > 1.5 / rate) | (np.diff(data.run) != 0)
    stretches = np.split(np.arange(data.time.size), np.flatnonzero(gap) + 1)
    cut = [np.array_split(p, -(-p.size // LONGEST)) for p in stretches if p.size >= SHORTEST]
    return [p for parts in cut for p in parts]


def residual_spectra(residual: np.ndarray, stretches: list[np.ndarray], rate: float):
    """Two-sided power spectral density of each joint's residual, Welch over every stretch at least
    one segment long (``SEGMENT``, or the longest stretch if shorter).

    Args:
        residual: (N, n) [Nm]; stretches: contiguous instants (:func:`pieces`); rate: f_s [Hz].

    Returns:
        frequencies (F,) [Hz] ascending and S (F, n) [Nm²/Hz].
    """
    length = min(int(SEGMENT * rate), max(p.size for p in stretches))
    total, weight = 0.0, 0
    for rows in [p for p in stretches if p.size >= length]:
        f, S = signal.welch(residual[rows], fs=rate, nperseg=length, detrend=False, return_onesided=False, axis=0)
        total, weight = total + rows.size * S, weight + rows.size
    order = np.argsort(f)
    return f[order], total[order] / weight


def middle(data: Dataset, x: np.ndarray, effects: list[Term], weights: np.ndarray | None, rate: float) -> np.ndarray:
    """(m, m) AᵀW Σ W A of the module docstring for the model [Y_B, ``effects``] (its unknowns' order,
    as :meth:`~excite_cli.identification.fitting.normal.NormalEquations.system`) fitted with
    coefficients x (m,) and joint weights w (n,) (W = w_j² on joint j's rows; None: 1), on ``data`` at
    ``rate`` [Hz]."""
    n = data.n
    stretches = pieces(data, rate)
    residual = data.tau.reshape(-1, n) - predict(data, x, effects)
    frequency, S = residual_spectra(residual, stretches, rate)
    w = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
    out = np.zeros((x.size, x.size))
    for rows in stretches:
        for j in np.flatnonzero(w):
            A = data.joint_rows(rows, j, effects)
            spectrum = np.fft.fft(A, axis=0)
            lam = rate * np.interp(np.fft.fftfreq(rows.size, 1.0 / rate), frequency, S[:, j])
            # W Σ W: w_j² on each side
            out += w[j] ** 4 * (spectrum.conj().T @ (lam[:, None] * spectrum)).real / rows.size
    return out
