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

A step tries every addition and shape change (50–150 moves), and one by one at 95 % some useless
move passes in most steps; the search then takes the best of them. With :data:`FAMILY_FOLDS` or more
folds a step therefore takes an addition or shape change only when one of them passes tested
together with the others (:func:`family_critical`): each move's t moderated by the family's median
variance (Smyth, Stat. Appl. Genet. Mol. Biol. 2004), the critical t that of the family's largest t
under the 2^K sign patterns of the folds (Westfall & Young, "Resampling-Based Multiple Testing"
1993, single-step maxT), so that a step where no move helps admits one in about 5 % of the cases
whatever the number of moves and their correlation. The move taken is of those that pass their own
test: a real effect whose gain differs between recordings (a Stribeck term that matters on the
trajectories slow on its joint) has a large mean and a large spread, and tested in the family it
lost to a small steady stand-in (held friction). Of them the one to the smallest model
(:func:`model_size`), of one size the lowest J, unless a larger one passes the test against it,
tested together with every larger move (the best of a grid of shape velocities is a selection too;
:meth:`~excite_cli.identification.choice.search.StepwiseSearch._taken`). Removals are one
hypothesis each and keep the plain test. With 4 folds the family's level could be no lower than
1/16: tried, it refused the true Stribeck term of a simulated Panda in 3 of 10 runs on 4 recordings,
so 4 folds test each move alone.

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
from typing import NamedTuple

import numpy as np
import scipy.stats

from excite_cli.identification.config import IdentificationConfig
from excite_cli.identification.effects import Term

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
#: The fewest folds the moves of a step are tested together on (the family-wise error): the 2^K sign
#: patterns of 4 folds are 16, whose smallest share 1/16 is above 5 %, so 4 folds test each move alone.
FAMILY_FOLDS = 5


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


class Family(NamedTuple):
    """The moves of one step tested together (:func:`family_critical`): the critical moderated t and
    the family's variance s₀² of d [log units²] each move's own is pooled with."""

    critical: float
    variance: float


def paired_gain(before: np.ndarray, after: np.ndarray, family: Family | None = None) -> tuple[float, float]:
    """The mean over folds of d_k = log e_k(before) − log e_k(after) and its margin c · s/√K (module
    docstring): c = t_{0.95, K−1} and s = sd(d), or in a ``family`` its critical t and the moderated
    s = √((s₀² + sd(d)²)/2) (:func:`family_critical`).

    Args:
        before, after: (K,) fold errors [%] of two models (K ≥ 2), positive.

    Returns:
        (mean, margin), both in log units: the move passes when mean > margin and mean > :data:`FLOOR`.
    """
    d = np.log(np.maximum(before, 1e-12)) - np.log(np.maximum(after, 1e-12))
    k = d.size
    if family is None:
        margin = scipy.stats.t.ppf(LEVEL, k - 1) * d.std(ddof=1) / np.sqrt(k)
    else:
        margin = family.critical * np.sqrt((family.variance + d.var(ddof=1)) / 2.0 / k)
    return float(d.mean()), float(margin)


def family_critical(before: np.ndarray, after: np.ndarray) -> Family | None:
    """The moves tried at one step tested together (module docstring: the family-wise error), or None
    below :data:`FAMILY_FOLDS` folds (each move's own t-test then).

    Each move's t is moderated: its variance of d pooled half and half with the family's median
    variance s₀² (Smyth 2004: few folds give each move's variance few degrees of freedom, and a move
    whose folds happen to agree would otherwise win by its small spread). The critical t is that of
    the largest t of the family under the 2^K sign patterns of the folds (one flip of fold k for every
    move, which keeps the moves' correlation; Westfall & Young 1993, single-step maxT): a move passes
    when at most 5 % of the patterns give some move a t as large.

    Args:
        before: (K,) fold errors [%] of the model the moves start from; after: (M, K) each move's.
    """
    k = before.size
    if k < FAMILY_FOLDS or after.shape[0] == 0:
        return None
    d = np.log(np.maximum(before, 1e-12))[None, :] - np.log(np.maximum(after, 1e-12))  # (M, K)
    signs = 1.0 - 2.0 * ((np.arange(2**k)[:, None] >> np.arange(k)) & 1)  # (2^K, K), the first all +1
    means = signs @ d.T / k  # (2^K, M)
    variance = np.maximum((d**2).sum(axis=1) - k * means**2, 0.0) / (k - 1)
    pooled = np.median(variance, axis=1)  # (2^K,) s₀² of each pattern
    t = means / np.maximum(np.sqrt((pooled[:, None] + variance) / 2.0 / k), 1e-15)
    largest = np.sort(t.max(axis=1))[::-1]
    return Family(float(largest[int(np.floor((1.0 - LEVEL) * largest.size))]), float(pooled[0]))


def passes(before: np.ndarray, after: np.ndarray, family: Family | None = None) -> bool:
    """Whether the move from fold errors ``before`` to ``after`` (K,) passes the paired test (module
    docstring), tested in its step's ``family`` if given (:func:`family_critical`)."""
    mean, margin = paired_gain(before, after, family)
    return mean > max(margin, FLOOR)


def as_percent(log_gain: float) -> float:
    """A gain in log units as the cut [%] of the error it makes: 100 (1 − e^(−g))."""
    return float(100.0 * -np.expm1(-log_gain))


def model_size(terms: list[Term]) -> int:
    """A model's size under the paired test: its terms and the shape velocities chosen for them from
    their grid (Stribeck's v_s, held friction's v_h), each fitted by the same folds."""
    return len(terms) + sum(t.shape is not None for t in terms)


def simplest(J: np.ndarray, folds: np.ndarray, sizes: np.ndarray, columns: list[int]) -> tuple[int, int]:
    """The (model, fit) of the fits ``columns`` kept by the paired test: each model's lowest-J pair among
    them, the models in order of their pair's size (of one size, the lowest J first: the folds' own
    preference where the test cannot choose; then by index), a larger one replacing the kept one only
    when it passes the test against it (module docstring).

    Args:
        J: (m, f) each pair's objective; folds: (m, f, K) each pair's fold errors [%]; sizes: (m, f)
            the terms each pair adds (a consistent fit does not count the armature it holds anyway).
    """
    best = [(k, min(columns, key=lambda f: np.nan_to_num(J[k, f], nan=np.inf))) for k in range(J.shape[0])]
    order = sorted(range(len(best)), key=lambda k: (sizes[best[k]], np.nan_to_num(J[best[k]], nan=np.inf), k))
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


def effect_count(terms: list[Term], declared: int, weights: tuple[float, float]) -> float:
    """p: the effects ``terms`` add beyond their first ``declared``, a coupled one counting as
    ``weights[0]`` effects (its price is log(1 + ``coupling_improvement``): it ties two joints and,
    unlike a joint's own effect, could stand in for effects of both) and a position-dependent one as
    ``weights[1]`` (log(1 + ``position_improvement``): a function of q can follow a residual of the
    positions the fit data visit, whatever its cause)."""
    coupled, position = weights
    return sum(coupled if t.coupling is not None else position if t.kind.position else 1.0 for t in terms[declared:])


def effect_weights(cfg: IdentificationConfig) -> tuple[float, float]:
    """How many effects a coupled and a position-dependent one count as: log(1 + coupling_improvement)
    and log(1 + position_improvement) over log(1 + min_improvement)."""
    unit = max(np.log1p(cfg.min_improvement), 1e-12)
    return float(np.log1p(cfg.coupling_improvement) / unit), float(np.log1p(cfg.position_improvement) / unit)


def priced_objective(cv_error, effects, min_improvement: float):
    """J = log CV + p · log(1 + min_improvement) (module docstring: the price) of CV errors [%] with p
    added effects; scalars or arrays that broadcast."""
    return np.log(np.maximum(cv_error, 1e-12)) + np.asarray(effects) * np.log1p(min_improvement)
