"""Tracing the residual to the effects the rigid-body model lacks: a stepwise search over effect
terms scored by blocked cross-validation of the fit data (:mod:`~excite_cli.identification.choice.crossval`).
The validation data (``validation`` runs, odd time blocks) take no part: they stay untouched for
the reported error.

The search minimizes an objective J(M) under the admission rule its folds allow
(:mod:`~excite_cli.identification.choice.admission`): with folds of four or more distinct
recordings, every effect must pass a paired test over the folds (the folds agree it helps by more
than they disagree); with time blocks of one recording or fewer recordings, which cannot judge a
new effect, every
effect must lower the cross-validated error by the fraction ``min_improvement`` (default 2 %;
:mod:`~excite_cli.identification.choice.search`). A move adds a candidate term,
removes an added term, or changes the shape velocity of a Stribeck or held term (the profile search
over its grid; such a move is judged as an addition, or it would chase noise
for free); the allowed move that lowers J most is taken, and the search stops when none is allowed,
so it ends in a model no single move improves and cannot cycle (under the paired test no model is
visited twice). Greedy forward selection alone depends on
its path: a joint whose Coulomb friction is missing bends the shared base parameters, and adding it
later can make another joint's error worse first. So the search runs from three starts (the declared
effects alone, plus Coulomb friction on every joint, plus Coulomb and viscous friction on every
joint) and keeps the end with the lowest J (under the paired test: the fewest terms, unless a larger
end passes the test against it; of searches ending at the same model, the first). On distinct
recordings each end keeps an added term only when its estimate is clear of zero in the reported fit
(:mod:`~excite_cli.identification.choice.estimates`).
Candidates whose columns lie in the span of the rigid-body model (e.g. the armature of a joint whose
rotor inertia regroups with a link's) are not separately identifiable and are skipped. Every fit,
in the folds and the final one, uses the same per-joint weights (WLS: 1/σ_j of the rigid-body fit,
Gautier 1997) and keeps Coulomb, viscous and armature coefficients ≥ 0 (the consistent fit's bounds,
:data:`~excite_cli.effects.NONNEGATIVE`), so the reported model is exactly the one the
search scored and no effect is chosen for a coefficient the reported fit cannot have.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from excite_cli.effects import EFFECTS
from excite_cli.identification.choice.admission import (
    FAMILY_FOLDS,
    Admission,
    admission_of,
    effect_weights,
    model_size,
    simplest,
)
from excite_cli.identification.choice.crossval import CrossValidation
from excite_cli.identification.choice.estimates import Estimates
from excite_cli.identification.choice.search import LIKELY_FRICTION, StepwiseSearch
from excite_cli.identification.choice.search_record import Search, Step
from excite_cli.identification.config import IdentificationConfig
from excite_cli.identification.data_config import TransmissionConfig
from excite_cli.identification.effects import Term, rotor_terms
from excite_cli.identification.fitting.channels import without_dead_rows
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import Fit, joint_weights, least_squares
from excite_cli.identification.fitting.normal import ABSORBED, NormalEquations, outside_fraction

#: Starts of the search beyond the declared effects: friction a real joint is most likely to have.
STARTS = {
    "declared effects": (),
    "Coulomb on every joint": ("coulomb",),
    "Coulomb and viscous on every joint": LIKELY_FRICTION,
}


@dataclass
class Selection:
    """Outcome of the effect selection.

    Attributes:
        terms: the chosen terms, the declared ones first.
        declared: how many of ``terms`` were declared in the config.
        fit: least squares of [Y_B, terms] on all fit data (base parameters first).
        rigid: least squares of the rigid-body model alone.
        weights: (n,) the joints' weights (WLS) or None (LS), the same in every fit.
        cv_rigid, cv_error: CV error [%] of the rigid-body model and of the chosen one.
        cv_joint: (n,) the chosen model's CV error per joint [%].
        searches: the search from every start; ``chosen`` indexes the one kept.
        at_start: the kept model is that search's start, not its end (chosen with the fit,
            :mod:`~excite_cli.identification.choice.fit_choice`).
        absorbed: candidates skipped as not separately identifiable.
        cross_validation: the folds every model was scored on, for scoring other fits of the model.
        min_improvement: the price of an effect (a fraction); effect_weights: the effects a coupled
            and a position-dependent one count as (:func:`effect_count`); both under the price only.
        admission: how the search admitted terms: a paired test over folds of distinct recordings,
            or the price (:mod:`~excite_cli.identification.choice.admission`).
        normal: the fit data's normal equations (every candidate and every joint's armature: the rotors of
            :mod:`~excite_cli.identification.choice.consistent_model`), for refitting other models.
        estimates: the reported fit of any model on these data and its terms' distance from zero
            (:class:`~excite_cli.identification.choice.estimates.Estimates`); None without the fit
            data's rate and trajectories.
    """

    terms: list[Term]
    declared: int
    fit: Fit
    rigid: Fit
    weights: np.ndarray | None
    cv_rigid: float
    cv_error: float
    cv_joint: np.ndarray
    searches: list[Search]
    chosen: int
    absorbed: list[Term]
    cross_validation: CrossValidation
    min_improvement: float
    normal: NormalEquations
    effect_weights: tuple[float, float] = (1.0, 1.0)
    at_start: bool = False
    admission: Admission = Admission.PRICED
    estimates: Estimates | None = None

    @property
    def folds(self) -> int:
        """K, the number of cross-validation folds."""
        return self.cross_validation.folds

    @property
    def folds_by(self) -> str:
        """What each fold holds out: ``recording`` (a whole file) or ``time block``."""
        return "recording" if self.cross_validation.by_recording else "time block"

    @property
    def steps(self) -> list[Step]:
        """The steps of the kept search up to the kept model."""
        return [] if self.at_start else self.searches[self.chosen].steps


def candidate_terms(cfg: IdentificationConfig, n: int, couplings: list[tuple[float, ...]] = ()) -> list[Term]:
    """Every candidate term: each candidate effect on each joint, one per shape of shaped effects,
    and with ``motor`` among the candidates a whole motor (its inertia, Coulomb and viscous friction
    together) on each motor coordinate of ``couplings`` ((n,) weights each, :func:`motor_couplings`)."""
    single = [
        Term(e, j, s)
        for e in cfg.candidates
        if not EFFECTS[e].coupled
        for j in range(n)
        for s in (getattr(cfg, EFFECTS[e].shape_field) if EFFECTS[e].shape_field else [None])
    ]
    motors = [e for e in cfg.candidates if EFFECTS[e].coupled]
    coupled = [Term(e, int(np.flatnonzero(c)[0]), None, tuple(float(x) for x in c)) for c in couplings for e in motors]
    return single + coupled


def motor_couplings(transmission: TransmissionConfig | None, ratios: list[float], n: int) -> list[tuple[float, ...]]:
    """The motor coordinates coupled effects are proposed on: with a declared transmission, the rows
    of R = diag(N) C that turn with two joints or more (the coefficients are then the motor's own);
    without one, q_i + r q_(i+1) for every pair of neighbouring joints and ratio r of ``ratios`` (a
    coupled motor the data hold but nobody declared)."""
    if transmission is not None:
        return [tuple(float(x) for x in row) for row in transmission.reduction() if np.count_nonzero(row) > 1]
    out = []
    for i in range(n - 1):
        for r in ratios:
            c = np.zeros(n)
            c[i], c[i + 1] = 1.0, r
            out.append(tuple(c))
    return out


def kept_search(searches: list[Search]) -> int:
    """The index of the search whose end model has the lowest objective J; of searches ending at the
    same model (the same terms in any order) the first counts, so that the rounding of J, which depends
    on the order the terms were added in, never decides which search's steps a report shows.

    Raises:
        ValueError: no searches.
    """
    return min(_distinct_ends(searches), key=lambda k: (searches[k].objective, k))


def _distinct_ends(searches: list[Search]) -> list[int]:
    """The index of the first search ending at each model (the same terms in any order)."""
    first: dict[frozenset[Term], int] = {}
    for k, search in enumerate(searches):
        first.setdefault(frozenset(search.terms), k)
    return list(first.values())


def kept_by_test(searches: list[Search]) -> int:
    """Under the paired test: the index of the search whose end the paired test keeps, the ends in
    order of their size, a larger one kept only when it passes the test against the kept one
    (:func:`~excite_cli.identification.choice.admission.simplest`; of ends of one size the lowest J
    first: on a spring joint whose friction the torque noise hides, one search ended at a load-dependent
    Coulomb term and another at the joint's Coulomb friction, as many terms, and the first search's
    end was kept by its index); of ends at one model, the first.
    A model's size is its terms and the shape velocities the search chose for them from their grid
    (Stribeck's v_s, held friction's v_h): each is fitted by the same folds, so Coulomb friction with
    a negative Stribeck term at v_s 0.5 rad/s, which follows viscous friction over the velocities a
    slow joint reaches, is not kept over Coulomb and viscous friction unless it beats them."""
    index = _distinct_ends(searches)
    J = np.array([[searches[k].objective] for k in index])
    folds = np.array([[searches[k].folds] for k in index])
    sizes = [model_size(searches[k].terms) for k in index]
    return index[simplest(J, folds, np.array(sizes)[:, None], [0])[0]]


def select_effects(
    fit_data: Dataset,
    cfg: IdentificationConfig,
    declared: list[Term],
    margin: float,
    recordings: np.ndarray | None = None,
    fitted_offsets: bool = False,
    couplings: list[tuple[float, ...]] = (),
    scored: np.ndarray | None = None,
    say: Callable[[str], None] | None = None,
    uncertainty: tuple[float, np.ndarray] | None = None,
) -> Selection:
    """The stepwise search of the module docstring on the fit data.

    Args:
        fit_data: the fit data, with every candidate's block (two-stage ones included).
        cfg: candidates, ``min_improvement``, ``max_effects``, ``folds``, ``method``, shape grids.
        declared: terms in the model from the start, never removed.
        margin: [s] left out of a fold's fit around its held-out block (correlated samples).
        recordings: the recording of each run, indexed by ``fit_data.run``: two or more make the
            folds whole recordings; None: time blocks (:class:`CrossValidation`).
        fitted_offsets: every validation run is fitted too, so its offsets are known (recording folds
            fit the held-out runs' offsets).
        couplings: the motor coordinates of coupled candidates (:func:`motor_couplings`).
        scored: (n,) the joints the CV error is the mean over (a channel without signal is not).
        say: told each step of each search (:class:`StepwiseSearch`).
        uncertainty: the rate [Hz] of the fit data and the trajectory of each run (R,): where the folds
            are distinct recordings (the paired test), each search's end keeps an added term only when
            its estimate is clear of zero in the reported fit, judged by the spread between the
            recordings too from :data:`~excite_cli.identification.choice.admission.FAMILY_FOLDS` folds
            on (:mod:`~excite_cli.identification.choice.estimates`); None: not judged.
    """
    n = fit_data.n
    candidates = [t for t in candidate_terms(cfg, n, couplings) if t not in declared and t in fit_data.blocks]
    # the rotors the consistent fit holds beside any model (consistent_model): in every system, never candidates
    rotors = [t for t in rotor_terms(n, []) if t in fit_data.blocks and t not in declared + candidates]
    total = NormalEquations(fit_data, declared + candidates + rotors)
    weights = without_dead_rows(total, joint_weights(total, cfg.method == "wls"), scored)
    model = total.system(weights, declared)[0].shape[0]
    absorbed = [t for t in candidates if outside_fraction(total.system(weights, declared + [t])[0], model) < ABSORBED]
    candidates = [t for t in candidates if t not in absorbed]
    keys = declared + candidates + [t for t in total.size if t not in declared + candidates]
    cv = CrossValidation(fit_data, keys, weights, cfg.folds, margin, recordings, fitted_offsets, scored)
    rule = admission_of(cv.by_recording, cv.folds)
    spread = cv.folds >= FAMILY_FOLDS  # the spread of fewer recordings is itself too uncertain to judge by
    estimates = None if uncertainty is None else Estimates(total, weights, fit_data, *uncertainty, cfg.folds, spread)
    clear = estimates.clearance if estimates is not None and rule is Admission.PAIRED else None
    search = StepwiseSearch(cv, candidates, declared, cfg, rule, say, clear)
    searches, seen = [], []
    for name, effects in STARTS.items():
        start = declared + [t for t in candidates if t.effect in effects and t.shape is None and t.coupling is None]
        if any(set(start) == set(s) for s in seen):
            continue
        seen.append(start)
        searches.append(search.run(name, start))
    chosen = kept_search(searches) if search.rule is Admission.PRICED else kept_by_test(searches)
    terms = searches[chosen].terms
    return Selection(
        terms=terms,
        declared=len(declared),
        fit=least_squares(total, terms, weights),
        rigid=least_squares(total, [], weights),
        weights=weights,
        cv_rigid=cv.error([])[0],
        cv_error=searches[chosen].cv_error,
        cv_joint=cv.error(terms)[1],
        searches=searches,
        chosen=chosen,
        absorbed=absorbed,
        cross_validation=cv,
        min_improvement=cfg.min_improvement,
        normal=total,
        effect_weights=effect_weights(cfg),
        admission=search.rule,
        estimates=estimates,
    )
