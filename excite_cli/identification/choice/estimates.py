"""The kept model's estimates as the report gives them, and the rule that a term the report cannot
tell from zero is not kept.

The reported standard deviations are two (:func:`reported_fit`): the noise's, from the sandwich of
the residuals' spectra (:mod:`~excite_cli.identification.fitting.noise`), and the spread between the
distinct trajectories of the fit data, model error included (between time blocks with fewer than
three; :mod:`~excite_cli.identification.fitting.model_error`). An added term is kept only when one
of its coefficients is at least :data:`CLEAR` times the larger of the two from zero (with ``spread``
off, as on four recordings, whose spread has three degrees of freedom, the noise's alone): the search's
tests judge a move by the folds' errors, and a term that passes them by chance, or stands in for
another term of its joint, leaves an estimate within its own uncertainty of zero (on simulated UR10s
and Pandas, ``bench/admission.py``: the load-dependent Coulomb, Stribeck, held, asymmetric friction
and motor-coupling terms the truth lacks were admitted at 0.8–3.2 of these standard deviations, all
but one under 3; every true friction term stood at 4.0 or more). A coefficient held at its bound 0
has no two-sided deviation and counts as 0.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from excite_cli.identification.choice.crossval import fold_assignment
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import Fit, least_squares
from excite_cli.identification.fitting.model_error import between_time_blocks, between_trajectories
from excite_cli.identification.fitting.noise import middle
from excite_cli.identification.fitting.normal import NormalEquations

#: An added term's clearest coefficient must be this many of its standard deviations from zero.
CLEAR = 3.0


def reported_fit(
    normal: NormalEquations,
    terms: list[Term],
    weights: np.ndarray | None,
    fit_data: Dataset,
    rate: float,
    clusters: np.ndarray,
    folds: int,
) -> Fit:
    """The model [Y_B, ``terms``]'s least-squares fit as reported: its standard deviations from the
    noise the residuals show (the sandwich of :mod:`~excite_cli.identification.fitting.noise`,
    ``rate`` [Hz]), and beside them the spread between the distinct trajectories of the fit data
    (``clusters``: (R,) the trajectory of each configured run) when there are 3 or more, else between
    the ``folds`` time blocks of each trajectory's runs
    (:mod:`~excite_cli.identification.fitting.model_error`); a coefficient held at its bound has
    neither. ``normal``: the fit data's normal equations; ``weights``: (n,) the joints' (None: 1)."""
    x = least_squares(normal, terms, weights).x
    fit = least_squares(normal, terms, weights, middle=middle(fit_data, x, terms, weights, rate))
    variance, spread_by = between_trajectories(fit_data, fit.x, terms, weights, clusters), "trajectories"
    count = np.unique(clusters[np.unique(fit_data.run)]).size
    if variance is None:
        block, _ = fold_assignment(fit_data.time, fit_data.run, folds, 0.0)
        variance, count = between_time_blocks(fit_data, fit.x, terms, weights, block, clusters)
        spread_by = "time blocks"
    held = fit.held if fit.held.size else False
    return replace(fit, between=np.where(held, np.nan, np.sqrt(variance)), groups=int(count), spread_by=spread_by)


def clearance(fit: Fit, terms: list[Term], sizes: dict[Term, int], spread: bool = True) -> dict[Term, float]:
    """Each of ``terms``' clearest coefficient's |value| over the larger of its two reported standard
    deviations (module docstring; without ``spread`` the noise's alone), in the fit
    (:func:`reported_fit`) of the model [Y_B, ``terms``] whose terms have ``sizes`` coefficients each
    (the base parameters first)."""
    std = fit.std if fit.between is None or not spread else np.fmax(fit.std, fit.between)
    ratio = np.where(np.isfinite(std) & (std > 0), np.abs(fit.x) / np.where(std > 0, std, 1.0), 0.0)
    ends = fit.x.size - sum(sizes[t] for t in terms) + np.cumsum([0] + [sizes[t] for t in terms])
    return {t: float(ratio[lo:hi].max(initial=0.0)) for t, lo, hi in zip(terms, ends[:-1], ends[1:])}


class Estimates:
    """The reported fit of any model on one selection's data, and how clear of zero its terms are.

    Args:
        normal: the fit data's normal equations (every candidate); weights: (n,) the joints' (None: 1).
        fit_data, rate, clusters, folds: as :func:`reported_fit`.
        spread: judge by the larger of the noise's deviation and the spread between the recordings
            (five or more), or by the noise's alone (:func:`clearance`).
    """

    def __init__(
        self,
        normal: NormalEquations,
        weights: np.ndarray | None,
        fit_data: Dataset,
        rate: float,
        clusters: np.ndarray,
        folds: int,
        spread: bool = True,
    ):
        self.normal, self.weights, self.data = normal, weights, fit_data
        self.rate, self.clusters, self.folds, self.spread = rate, clusters, folds, spread

    def reported(self, terms: list[Term]) -> Fit:
        """:func:`reported_fit` of the model [Y_B, ``terms``]."""
        return reported_fit(self.normal, terms, self.weights, self.data, self.rate, self.clusters, self.folds)

    def clearance(self, terms: list[Term], asked: list[Term]) -> dict[Term, float]:
        """:func:`clearance` of the ``asked`` terms in the model [Y_B, ``terms``]."""
        ratios = clearance(self.reported(terms), terms, self.normal.size, self.spread)
        return {t: ratios[t] for t in asked}
