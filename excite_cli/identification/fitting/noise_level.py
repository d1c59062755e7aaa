"""The torque noise's level against the torque, measured from a recording: per joint
σ²(τ) = a² + (ρ τ)², an absolute part a [Nm] (a torque sensor's, a current reading's floor) and a
part ρ [1] growing with the torque (a motor current's: torque-constant and gear errors scale with the
load), fitted to the reported model's residual r on the fit data (its error away from them is model
error, not noise) by maximum likelihood of
r ~ N(0, a² + ρ² τ̂²) (τ̂ the model's predicted torque: the measured one carries the noise itself,
which would correlate r² with τ²).

The residual is low-passed and decimated as every column is (:mod:`~excite_cli.identification.measured.preprocessing`):
white noise of variance σ² at the recording's rate leaves σ² g, g = (1/π)∫₀^π |H(e^{iω})|⁴ dω for the
zero-phase filter's |H|² (:func:`noise_gain`). Each instant's residual is divided by √g of its run's
filter, so a and ρ are the noise of the recording's own samples, as a data sheet gives it (model error
is in it too: the design weighs rows by what the model leaves unexplained).

Their standard deviations are from a delete-one-block jackknife over :data:`BLOCKS` contiguous
blocks of the fit data (Künsch 1989: contiguous blocks keep the residual's correlation in
time, which a per-sample Fisher information would ignore). The data prefer noise growing with the
torque when ρ is at least :data:`CLEAR` of its standard deviations above zero, else absolute noise.

Where the growing part dominates, a is poorly determined and often fitted at 0, where the jackknife
has no spread either. What the next design may trust is the largest a the data cannot rule out: a's
one-sided 95 % upper bound from the profile likelihood (ρ re-fitted at each a; Wilks: −2 log of the
likelihood ratio at most :data:`UPPER_BOUND`, Venzon & Moolgavkar 1988), the samples taken as
independent.

Where some joint's noise grows with the torque, the model's fit weighed each joint's rows alike, so the
noise of its large-torque rows enters the estimates and, through them, the residual of its small-torque
rows, where it reads as an absolute floor several times the true one. The noise is then measured
again (:func:`measured_noise`): on the residual of the model refitted with each sample weighed by the
inverse of the noise just measured at its predicted torque, twice (:data:`REWEIGHTINGS`: feasible
generalized least squares iterated, Carroll, Wu & Ruppert 1988, "The effect of estimating weights in
weighted least squares", JASA 83), a taken at its upper bound so that no sample's weight is
unbounded.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import optimize, signal

#: Contiguous blocks of the jackknife.
BLOCKS = 10
#: Standard deviations above zero from which ρ counts as present.
CLEAR = 3.0
#: −2 log likelihood ratio of a's one-sided 95 % upper bound: the χ²₁ quantile at 0.90.
UPPER_BOUND = 2.706
#: Fits reweighted by the noise measured (:func:`measured_noise`): Carroll, Wu & Ruppert (1988) find
#: that weights estimated once leave the estimates' variance well above that of known weights, and
#: recommend at least two cycles.
REWEIGHTINGS = 2


@dataclass(frozen=True)
class NoiseLevel:
    """One joint's fitted noise σ²(τ) = a² + (ρ τ)² at the recording's own rate.

    Attributes:
        absolute: a [Nm]; absolute_std: its jackknife standard deviation [Nm].
        relative: ρ [1]; relative_std: its jackknife standard deviation [1].
        absolute_upper: a's one-sided 95 % profile-likelihood upper bound [Nm] (≥ a).
    """

    absolute: float
    absolute_std: float
    relative: float
    relative_std: float
    absolute_upper: float

    @property
    def preferred(self) -> str:
        """``relative`` (ρ at least :data:`CLEAR` standard deviations above zero) or ``absolute``."""
        return "relative" if self.relative >= CLEAR * self.relative_std and self.relative > 0 else "absolute"


def noise_gain(sos: np.ndarray) -> float:
    """g [1]: the variance a zero-phase (forward-backward) pass of the filter ``sos`` (scipy's second-
    order sections) leaves of white noise, (1/π)∫₀^π |H(e^{iω})|⁴ dω (Parseval), on 8192 frequencies."""
    _, h = signal.sosfreqz(sos, worN=8192)
    return float(np.mean(np.abs(h) ** 4))


def _scaled(r: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float]:
    """u = (r/s)², t² = (τ/l)² on the scales s, l of r's and τ's RMS, and s, l."""
    scale, level = float(np.sqrt(np.mean(r**2))) or 1.0, float(np.sqrt(np.mean(tau**2))) or 1.0
    return (r / scale) ** 2, (tau / level) ** 2, scale, level


def _deviance(v: np.ndarray, u: np.ndarray, t2: np.ndarray) -> tuple[float, np.ndarray]:
    """−2 log likelihood (less a constant) of scaled residuals u of variance v₀ + v₁ t², and its gradient."""
    var = np.maximum(v[0] + v[1] * t2, 1e-12)
    d = 1.0 / var - u / var**2  # ∂/∂var of log var + u / var
    return float(np.sum(np.log(var) + u / var)), np.array([d.sum(), (d * t2).sum()])


def _scaled_fit(u: np.ndarray, t2: np.ndarray) -> tuple[np.ndarray, float]:
    """The scaled (a², ρ²) ≥ 0 of largest likelihood (the moment fit of u on [1, t²] starts it) and its deviance."""
    start = np.linalg.lstsq(np.column_stack([np.ones_like(t2), t2]), u, rcond=None)[0]
    start = np.maximum(start, 1e-3 * max(start.max(), 1.0))
    best = optimize.minimize(_deviance, start, (u, t2), jac=True, method="L-BFGS-B", bounds=[(0, None)] * 2)
    return best.x, float(best.fun)


def _likelihood_fit(r: np.ndarray, tau: np.ndarray) -> tuple[float, float]:
    """(a², ρ²) maximizing the Gaussian likelihood of residuals r (N,) of variance a² + ρ²τ² (both ≥ 0)."""
    u, t2, scale, level = _scaled(r, tau)
    x, _ = _scaled_fit(u, t2)
    return float(x[0] * scale**2), float(x[1] * (scale / level) ** 2)


def _upper_bound(u: np.ndarray, t2: np.ndarray, x: np.ndarray, best: float) -> float:
    """The scaled a²'s one-sided 95 % profile-likelihood upper bound: the a² above the fitted x₀ (x, of
    deviance ``best``: :func:`_scaled_fit`) at which ρ re-fitted leaves a deviance :data:`UPPER_BOUND`
    above the best."""
    # ρ² beyond which the variance exceeds 10 × r's, or twice the fitted one where that is larger (noise
    # growing steeply at small torques with a few large ones the model follows: the fit lies beyond)
    largest = max(10.0 * u.mean() / max(t2.mean(), 1e-12), 2.0 * x[1])

    def excess(a2: float) -> float:
        profile = optimize.minimize_scalar(
            lambda rho2: _deviance(np.array([a2, rho2]), u, t2)[0], bounds=(0.0, largest), method="bounded"
        )
        return min(profile.fun, _deviance(np.array([a2, 0.0]), u, t2)[0]) - best - UPPER_BOUND

    high = max(x[0], 1e-3)
    while excess(high) < 0:
        high *= 2.0
    return float(optimize.brentq(excess, x[0], high, xtol=1e-6))


def fit_noise_level(residual: np.ndarray, torque: np.ndarray, gain: np.ndarray) -> NoiseLevel:
    """a, ρ and their standard deviations of one joint, and a's upper bound.

    Args:
        residual: (N,) [Nm] measured minus predicted torque on the fit data, in time order.
        torque: (N,) [Nm] the model's predicted torque at the same instants.
        gain: (N,) the noise gain g of each instant's filter (:func:`noise_gain`), > 0.

    Raises:
        ValueError: fewer than 2 × :data:`BLOCKS` instants (the caller reports no noise level then).
    """
    if residual.size < 2 * BLOCKS:
        raise ValueError(f"{residual.size} instants; the jackknife needs at least {2 * BLOCKS}")
    r = residual / np.sqrt(gain)
    u, t2, scale, level = _scaled(r, torque)
    x, best = _scaled_fit(u, t2)
    a2, rho2 = x[0] * scale**2, x[1] * (scale / level) ** 2
    edges = np.linspace(0, r.size, BLOCKS + 1).astype(int)
    keep = [np.r_[0:lo, hi : r.size] for lo, hi in zip(edges[:-1], edges[1:])]
    left_out = np.sqrt(np.array([_likelihood_fit(r[k], torque[k]) for k in keep]))
    std = np.sqrt((BLOCKS - 1) / BLOCKS * ((left_out - left_out.mean(axis=0)) ** 2).sum(axis=0))
    upper = float(np.sqrt(_upper_bound(u, t2, x, best)) * scale)
    return NoiseLevel(float(np.sqrt(a2)), float(std[0]), float(np.sqrt(rho2)), float(std[1]), upper)


def measured_noise(
    measured: np.ndarray,
    predicted: np.ndarray,
    gain: np.ndarray,
    live: np.ndarray,
    refit: Callable[[np.ndarray], np.ndarray],
) -> list[NoiseLevel | None]:
    """Each ``live`` joint's noise (:func:`fit_noise_level`) on the residual of the model's ``predicted``
    torques; while any joint's noise grows with the torque, at most :data:`REWEIGHTINGS` times again
    on the residual of ``refit`` with each sample weighed by the noise last measured (module docstring).

    Args:
        measured: (N, n) [Nm] the measured torques on the fit data, in time order; predicted: (N, n)
            [Nm] the model's.
        gain: (N,) each instant's noise gain g (:func:`noise_gain`), > 0.
        live: (n,) bool, the joints to measure (None for the others).
        refit: the model refitted with weights (N, n) [1/Nm] on its samples, returning its predicted
            torques (N, n) [Nm].

    Raises:
        ValueError: fewer than 2 × :data:`BLOCKS` instants.
    """
    levels = _levels(measured - predicted, predicted, gain, live)
    for _ in range(REWEIGHTINGS):
        if not any(level is not None and level.preferred == "relative" for level in levels):
            break
        rms = np.sqrt(np.mean((measured - predicted) ** 2, axis=0) / np.mean(gain))
        sigma = np.empty_like(predicted)
        for j, level in enumerate(levels):  # each sample's noise at the filtered data's rate: × √g
            a, rho = (rms[j], 0.0) if level is None else (level.absolute_upper, level.relative)
            floor = max(a, 1e-6 * max(rms[j], 1e-12))
            sigma[:, j] = np.sqrt(floor**2 + (rho * predicted[:, j]) ** 2) * np.sqrt(gain)
        predicted = refit(1.0 / sigma)
        levels = _levels(measured - predicted, predicted, gain, live)
    return levels


def _levels(residual: np.ndarray, predicted: np.ndarray, gain: np.ndarray, live: np.ndarray) -> list[NoiseLevel | None]:
    """:func:`fit_noise_level` of each ``live`` joint's column of ``residual`` (N, n), None for the others."""
    return [fit_noise_level(residual[:, j], predicted[:, j], gain) if live[j] else None for j in range(len(live))]
