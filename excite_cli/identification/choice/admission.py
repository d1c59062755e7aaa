"""How the effect search admits a term: by what the folds can show, or by a price when they cannot.

**Folds that are distinct recordings** (four or more, each a recording or the twin recordings of one
trajectory: :class:`~excite_cli.identification.choice.crossval.CrossValidation`) each hold motion,
load and temperature the other folds' fit never saw, so each is an independent test of a model on a
new recording. A move from model M to M' changes fold k's error e_k by

    d_k = log e_k(M) − log e_k(M'),

and the move is admitted when the folds agree it helps by more than they disagree among themselves:
a one-sided paired t-test over the K folds (Student 1908; Dietterich 1998 for comparing fitted
models on the same folds),

    mean(d) > t_{0.95, K−1} · sd(d) / √K   and   mean(d) > 0.001,

whatever kind of effect it adds (no price per kind; the floor of 0.1 % only keeps out moves that
change nothing, such as a coefficient held at its bound). A term whose keeping no longer passes the
test is removed. Of two models, the one with more terms is kept only when it passes the test against
the other (:func:`simplest`): the ends of the searches, and the models and fits compared together. A gain every fold
shares is admitted however small (a spring worth 5 %, a low-speed friction term worth 1.5 %); a gain
one fold makes and another loses is not, however large its mean.

**Time blocks of one recording** share its motion: for a periodic excitation each block repeats the
phases the other blocks saw (the real Panda run: folds of one periodic run rewarded position terms
that cost on its unseen phases), so the folds cannot judge a new effect; nor can two or three
recordings, whose spread rests on one or two degrees of freedom (:data:`PAIRED_FOLDS`). Then the
prior rule admits:
a term must cut the pooled cross-validated error by the fraction ``min_improvement`` (a coupled one
``coupling_improvement``, a position-dependent one ``position_improvement``;
:mod:`~excite_cli.identification.choice.search`), and the report says so.
"""

from __future__ import annotations

from enum import StrEnum

import numpy as np
import scipy.stats

#: One-sided level of the paired test over folds.
LEVEL = 0.95
#: The smallest mean gain over folds [log units] a move must make to be admitted: 0.1 % of the error.
#: Below it a "gain" is the arithmetic's (a coefficient held at its bound changes no prediction).
FLOOR = 1e-3
#: The fewest distinct-recording folds a paired test is run on. With three the spread rests on two
#: degrees of freedom (the margin is 2.9 standard errors, itself known to a factor of about 2): on three
#: simulated recordings with Coulomb friction on every joint, one of them with viscous friction the
#: others lack, the test dropped the Coulomb friction of 3 of the 7 joints (tests/identification/
#: test_transfer.py); three recordings keep the price.
PAIRED_FOLDS = 4


class Admission(StrEnum):
    """How the search admits a term (module docstring)."""

    PAIRED = "paired test over distinct recordings"
    PRICED = "price per effect (time blocks, or fewer than 4 distinct recordings, cannot judge new effects)"

    @property
    def search_objective(self) -> str:
        """J of the search, in words."""
        if self is Admission.PAIRED:
            return "J = mean over folds of log e_k (each move passes a paired test over the folds)"
        return "J = log CV + p log(1 + min_improvement)"

    @property
    def fit_objective(self) -> str:
        """J of the models and fits scored together (:mod:`~excite_cli.identification.choice.fit_choice`)."""
        if self is Admission.PAIRED:
            return (
                "J = mean over folds of log e_k; a model with more effects only where it beats the smaller by "
                "a paired test over the folds, least squares only where it beats the consistent fit so"
            )
        return (
            "J = log CV + effects × log(1 + min_improvement) (least squares: + log(1 + least_squares_margin); "
            "a consistent fit's effects leave out armature, it holds every rotor)"
        )


def admission_of(by_recording: bool, folds: int) -> Admission:
    """The rule of folds that are whole recordings (``by_recording``) or time blocks, ``folds`` of them."""
    return Admission.PAIRED if by_recording and folds >= PAIRED_FOLDS else Admission.PRICED


def paired_gain(before: np.ndarray, after: np.ndarray) -> tuple[float, float]:
    """The mean over folds of d_k = log e_k(before) − log e_k(after) and its margin
    t_{0.95, K−1} sd(d)/√K (module docstring).

    Args:
        before, after: (K,) fold errors [%] of two models (K ≥ 2), positive.

    Returns:
        (mean, margin), both in log units: the move passes when mean > margin and mean > :data:`FLOOR`.
    """
    d = np.log(np.maximum(before, 1e-12)) - np.log(np.maximum(after, 1e-12))
    k = d.size
    margin = scipy.stats.t.ppf(LEVEL, k - 1) * d.std(ddof=1) / np.sqrt(k)
    return float(d.mean()), float(margin)


def passes(before: np.ndarray, after: np.ndarray) -> bool:
    """Whether the move from fold errors ``before`` to ``after`` (K,) passes the paired test (module docstring)."""
    mean, margin = paired_gain(before, after)
    return mean > max(margin, FLOOR)


def as_percent(log_gain: float) -> float:
    """A gain in log units as the cut [%] of the error it makes: 100 (1 − e^(−g))."""
    return float(100.0 * -np.expm1(-log_gain))


def simplest(J: np.ndarray, folds: np.ndarray, sizes: np.ndarray, columns: list[int]) -> tuple[int, int]:
    """The (model, fit) of the fits ``columns`` kept by the paired test: each model's lowest-J pair among
    them, the models in order of their pair's size (ties by index), a larger one replacing the kept one
    only when it passes the test against it (module docstring).

    Args:
        J: (m, f) each pair's objective; folds: (m, f, K) each pair's fold errors [%]; sizes: (m, f)
            the terms each pair adds (a consistent fit does not count the armature it holds anyway).
    """
    best = [(k, min(columns, key=lambda f: np.nan_to_num(J[k, f], nan=np.inf))) for k in range(J.shape[0])]
    order = sorted(range(len(best)), key=lambda k: (sizes[best[k]], k))
    kept = best[order[0]]
    for k in order[1:]:
        if passes(folds[kept], folds[best[k]]):
            kept = best[k]
    return kept


def paired_choice(J: np.ndarray, folds: np.ndarray, preferred: list[bool], sizes: np.ndarray) -> tuple[int, int]:
    """(model, fit) of the pairs scored J (m, f) on the folds (``folds``: (m, f, K) fold errors [%]):
    of the ``preferred`` (f,) fits (the consistent ones) the pair :func:`simplest` keeps, unless the
    pair it keeps of the others (least squares) beats it by the paired test; with one kind only, that
    kind's. ``sizes`` (m, f): the terms each pair adds (:func:`simplest`)."""
    first = [f for f, p in enumerate(preferred) if p]
    others = [f for f, p in enumerate(preferred) if not p]
    if not first or not others:
        return simplest(J, folds, sizes, first or others)
    kept, challenger = simplest(J, folds, sizes, first), simplest(J, folds, sizes, others)
    return challenger if passes(folds[kept], folds[challenger]) else kept
