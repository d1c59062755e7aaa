"""Tracing the residual to the effects the rigid-body model lacks: a stepwise search over effect
terms scored by blocked cross-validation of the fit data (:mod:`~excite_cli.identification.choice.crossval`).
The validation data (``validation`` runs, odd time blocks) take no part: they stay untouched for
the reported error.

The search minimizes

    J(M) = log CV(M) + p(M) · log(1 + min_improvement),

p(M) the number of terms the search added: every effect must lower the cross-validated error by
the fraction ``min_improvement`` (default 2 %) to stay in the model. A move adds a candidate term,
removes an added term, or changes the shape velocity of a Stribeck or held term (the profile search
over its grid; such a move must cut the error by ``min_improvement`` too, or it would chase noise
for free); the move that lowers J most is taken, and the search stops when none does, so it ends in
a model no single move improves and cannot cycle. Greedy forward selection alone depends on
its path: a joint whose Coulomb friction is missing bends the shared base parameters, and adding it
later can make another joint's error worse first. So the search runs from three starts (the declared
effects alone, plus Coulomb friction on every joint, plus Coulomb and viscous friction on every
joint) and keeps the end with the lowest J. Candidates whose columns lie in the span of the
rigid-body model (e.g. the armature of a joint whose rotor inertia regroups with a link's) are not
separately identifiable and are skipped. Every fit, in the folds and the final one, uses the same
per-joint weights (WLS: 1/σ_j of the rigid-body fit, Gautier 1997), so the reported model is exactly
the one the search scored.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from excite_cli.identification.choice.crossval import CrossValidation
from excite_cli.identification.config import IdentificationConfig
from excite_cli.identification.effects import EFFECTS, Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import Fit, joint_weights, least_squares
from excite_cli.identification.fitting.normal import ABSORBED, NormalEquations, outside_fraction

#: How a move is written: added, removed, shape changed.
MOVE_SIGNS = {"add": "+", "remove": "−", "shape": "~"}
#: Starts of the search beyond the declared effects: friction a real joint is most likely to have.
STARTS = {
    "declared effects": (),
    "Coulomb on every joint": ("coulomb",),
    "Coulomb and viscous on every joint": ("coulomb", "viscous"),
}


@dataclass(frozen=True)
class Step:
    """One move of the search.

    Attributes:
        move: ``add``, ``remove`` or ``shape`` (a Stribeck or held term's velocity changed).
        term: the term added, removed, or the new shape's term.
        terms: the model after the move.
        cv_error: CV(M) [%] after the move; before: CV(M) [%] before it.
        tried: every move considered at this step: (move, term, CV after [%]).
    """

    move: str
    term: Term
    terms: list[Term]
    cv_error: float
    before: float
    tried: list[tuple[str, Term, float]]

    def gain_of(self, cv_error: float) -> float:
        """The cut [%] of the CV error before this step that a move to ``cv_error`` [%] makes."""
        return 100.0 * (1.0 - cv_error / self.before)

    @property
    def gain(self) -> float:
        """The cut [%] of the CV error this step made."""
        return self.gain_of(self.cv_error)

    def label(self, joints: list[str]) -> str:
        """e.g. ``+ held panda_joint7 (v_h 0.1 rad/s)``."""
        return f"{MOVE_SIGNS[self.move]} {self.term.label(joints)}"


@dataclass
class Search:
    """The search from one start: its name, start model and its CV error [%], end model and its CV
    error [%] and objective J, the steps and why it stopped."""

    start: str
    initial: list[Term]
    initial_error: float
    terms: list[Term]
    cv_error: float
    objective: float
    steps: list[Step] = field(default_factory=list)
    stop: str = ""


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
        min_improvement: the price of an effect (a fraction).
        normal: the fit data's normal equations (every candidate), for refitting other models.
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
    at_start: bool = False

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


def objective(cv_error, effects, min_improvement: float):
    """J = log CV + p · log(1 + min_improvement) (module docstring) of CV errors [%] with p added
    effects; scalars or arrays that broadcast."""
    return np.log(np.maximum(cv_error, 1e-12)) + np.asarray(effects) * np.log1p(min_improvement)


def candidate_terms(cfg: IdentificationConfig, n: int) -> list[Term]:
    """Every candidate term: each candidate effect on each joint, one per shape of shaped effects."""
    return [
        Term(e, j, s)
        for e in cfg.candidates
        for j in range(n)
        for s in (getattr(cfg, EFFECTS[e].shape_field) if EFFECTS[e].shape_field else [None])
    ]


class _Search:
    """The moves and the objective J of one selection problem."""

    def __init__(self, cv: CrossValidation, candidates: list[Term], declared: list[Term], cfg: IdentificationConfig):
        self.cv, self.candidates, self.declared, self.cfg = cv, candidates, declared, cfg
        self.fixed = {(t.effect, t.joint) for t in declared}  # declared: never removed (their shape may move)
        self.penalty = np.log1p(cfg.min_improvement)
        self.cache: dict[frozenset, float] = {}

    def error(self, terms: list[Term]) -> float:
        key = frozenset(terms)
        if key not in self.cache:
            self.cache[key] = self.cv.error(terms)[0]
        return self.cache[key]

    def objective(self, terms: list[Term], error: float) -> float:
        return float(objective(error, len(terms) - len(self.declared), self.cfg.min_improvement))

    def cost(self, move: str, terms: list[Term], error: float) -> float:
        """J of the model a move leads to; a shape change pays the price of an effect as well."""
        return self.objective(terms, error) + (self.penalty if move == "shape" else 0.0)

    def moves(self, terms: list[Term]) -> list[tuple[str, Term, list[Term]]]:
        """(move, term, model after) of every allowed move from ``terms``."""
        family = {(t.effect, t.joint): t for t in terms}
        out = []
        if len(terms) - len(self.declared) < self.cfg.max_effects:
            out += [
                ("add", c, terms + [c])
                for c in self.candidates
                if (c.effect, c.joint) not in family
                and (c.kind.requires is None or (c.kind.requires, c.joint) in family)
            ]
        for t in terms:
            needed = any(u.kind.requires == t.effect and u.joint == t.joint for u in terms)
            if (t.effect, t.joint) not in self.fixed and not needed:
                out.append(("remove", t, [u for u in terms if u != t]))
            if t.shape is not None:
                out += [
                    ("shape", c, [c if u == t else u for u in terms])
                    for c in self.candidates
                    if c.effect == t.effect and c.joint == t.joint and c.shape != t.shape
                ]
        return out

    def run(self, name: str, start: list[Term]) -> Search:
        terms = list(start)
        error = self.error(terms)
        search = Search(name, list(terms), error, terms, error, self.objective(terms, error))
        while True:
            tried = [(move, term, after, self.error(after)) for move, term, after in self.moves(terms)]
            if not tried:
                search.stop = "no move left (every candidate is in the model)"
                break
            move, term, after, value = min(tried, key=lambda m: self.cost(m[0], m[2], m[3]))
            if self.cost(move, after, value) >= search.objective - 1e-12:
                search.stop = (
                    f"no addition, removal or shape change lowers the cross-validated error by "
                    f"min_improvement ({100 * self.cfg.min_improvement:g} %)"
                )
                if len(terms) - len(self.declared) >= self.cfg.max_effects:
                    search.stop = f"max_effects ({self.cfg.max_effects}) reached; no removal or shape change helps"
                break
            search.steps.append(Step(move, term, after, value, error, [(m, t, v) for m, t, _, v in tried]))
            terms, error = after, value
            search.objective = self.objective(terms, error)
        search.terms, search.cv_error = terms, error
        return search


def select_effects(
    fit_data: Dataset,
    cfg: IdentificationConfig,
    declared: list[Term],
    margin: float,
    oversampling: float = 1.0,
    recordings: np.ndarray | None = None,
    fitted_offsets: bool = False,
) -> Selection:
    """The stepwise search of the module docstring on the fit data.

    Args:
        fit_data: the fit data, with every candidate's block (two-stage ones included).
        cfg: candidates, ``min_improvement``, ``max_effects``, ``folds``, ``method``, shape grids.
        declared: terms in the model from the start, never removed.
        margin: [s] left out of a fold's fit around its held-out block (correlated samples).
        oversampling: samples per independent sample r (≥ 1) of the filtered data, for the
            standard deviations.
        recordings: the recording of each run, indexed by ``fit_data.run``: two or more make the
            folds whole recordings; None: time blocks (:class:`CrossValidation`).
        fitted_offsets: every validation run is fitted too, so its offsets are known (recording folds
            fit the held-out runs' offsets).
    """
    n = fit_data.n
    candidates = [t for t in candidate_terms(cfg, n) if t not in declared and t in fit_data.blocks]
    total = NormalEquations(fit_data, declared + candidates)
    weights = joint_weights(total, cfg.method == "wls")
    model = total.system(weights, declared)[0].shape[0]
    absorbed = [t for t in candidates if outside_fraction(total.system(weights, declared + [t])[0], model) < ABSORBED]
    candidates = [t for t in candidates if t not in absorbed]
    cv = CrossValidation(fit_data, declared + candidates, weights, cfg.folds, margin, recordings, fitted_offsets)
    search = _Search(cv, candidates, declared, cfg)
    searches, seen = [], []
    for name, effects in STARTS.items():
        start = declared + [t for t in candidates if t.effect in effects and t.shape is None]
        if any(set(start) == set(s) for s in seen):
            continue
        seen.append(start)
        searches.append(search.run(name, start))
    chosen = min(range(len(searches)), key=lambda k: searches[k].objective)
    terms = searches[chosen].terms
    return Selection(
        terms=terms,
        declared=len(declared),
        fit=least_squares(total, terms, weights, oversampling),
        rigid=least_squares(total, [], weights, oversampling),
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
    )
