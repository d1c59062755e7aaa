"""The stepwise search's moves and objective (:mod:`~excite_cli.identification.choice.selection`):

    J(M) = log CV(M) + p(M) · log(1 + min_improvement),

p(M) the effects the search added, a coupled one counting as log(1 + coupling_improvement) /
log(1 + min_improvement) effects and a position-dependent one as log(1 + position_improvement) /
log(1 + min_improvement). A move adds a candidate whose prerequisites are in the model,
removes an added term nothing depends on, or moves a Stribeck or held term along its velocity grid
or a coupled term along its ratio grid (paying an effect's price, or it would chase noise for free);
the move that lowers J most is taken until none does.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from excite_cli.identification.choice.crossval import CrossValidation
from excite_cli.identification.config import IdentificationConfig
from excite_cli.identification.effects import Term

#: How a move is written: added, removed, shape changed.
MOVE_SIGNS = {"add": "+", "remove": "−", "shape": "~"}


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


def objective(cv_error, effects, min_improvement: float):
    """J = log CV + p · log(1 + min_improvement) (module docstring) of CV errors [%] with p added
    effects; scalars or arrays that broadcast."""
    return np.log(np.maximum(cv_error, 1e-12)) + np.asarray(effects) * np.log1p(min_improvement)


class StepwiseSearch:
    """The moves and the objective J of one selection problem."""

    def __init__(
        self,
        cv: CrossValidation,
        candidates: list[Term],
        declared: list[Term],
        cfg: IdentificationConfig,
    ):
        self.cv, self.candidates, self.declared, self.cfg = cv, candidates, declared, cfg
        self.fixed = {t.family for t in declared}  # declared: never removed (their shape may move)
        self.penalty = np.log1p(cfg.min_improvement)
        self.cache: dict[frozenset, float] = {}

    def error(self, terms: list[Term]) -> float:
        key = frozenset(terms)
        if key not in self.cache:
            self.cache[key] = self.cv.error(terms)[0]
        return self.cache[key]

    def objective(self, terms: list[Term], error: float) -> float:
        p = effect_count(terms, len(self.declared), effect_weights(self.cfg))
        return float(objective(error, p, self.cfg.min_improvement))

    def cost(self, move: str, terms: list[Term], error: float) -> float:
        """J of the model a move leads to; a shape change pays the price of an effect as well."""
        return self.objective(terms, error) + (self.penalty if move == "shape" else 0.0)

    def moves(self, terms: list[Term]) -> list[tuple[str, Term, list[Term]]]:
        """(move, term, model after) of every allowed move from ``terms``."""
        family = {t.family: t for t in terms}
        out = []
        if len(terms) - len(self.declared) < self.cfg.max_effects:
            out += [
                ("add", c, terms + [c])
                for c in self.candidates
                if c.family not in family and (c.kind.requires is None or (c.kind.requires, *c.family[1:]) in family)
            ]
        for t in terms:
            needed = any(u.kind.requires == t.effect and u.family[1:] == t.family[1:] for u in terms)
            if t.family not in self.fixed and not needed:
                out.append(("remove", t, [u for u in terms if u != t]))
            if t.shape is not None or t.coupling is not None:  # along the shape velocity's or the ratio's grid
                out += [
                    ("shape", c, [c if u == t else u for u in terms])
                    for c in self.candidates
                    if c.family == t.family and c != t
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
