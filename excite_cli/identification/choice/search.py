"""The stepwise search's moves and objective (:mod:`~excite_cli.identification.choice.selection`),
under the admission rule of its folds (:mod:`~excite_cli.identification.choice.admission`).

A move adds a candidate whose prerequisites are in the model, removes an added term nothing depends
on, or moves a Stribeck or held term along its velocity grid or a coupled term along its ratio grid.

- **Paired test** (folds that are four or more distinct trajectories): an addition or a shape change
  must pass the paired test over the folds (and gain at least its 0.1 % floor), and from five folds
  on a step takes one only when one of them passes tested together with the others (the
  family-wise error: :func:`~excite_cli.identification.choice.admission.family_critical`); an added
  term whose keeping no longer passes it is removed (a start's friction terms the data do not need,
  a term a later one took over); of the moves allowed to a model not visited before, the one to the
  smallest model (its terms and shape velocities) with the lowest mean log fold error
  J(M) = mean_k log e_k(M) is taken, unless a larger one passes the test against it, tested
  together with every larger move (:meth:`StepwiseSearch._taken`).
- **Price** (time blocks of one recording): J(M) = log CV(M) + p(M) · log(1 + min_improvement),
  p(M) the effects the search added, a coupled one counting as log(1 + coupling_improvement) /
  log(1 + min_improvement) effects and a position-dependent one as log(1 + position_improvement) /
  log(1 + min_improvement); a shape change pays an effect's price (or it would chase noise for
  free); the move that lowers J most is taken.

Under the price every move lowers J; under the paired test no model is visited twice. Either way
the search cannot cycle, and it stops when no move is allowed. Given the reported fit's estimates
(on distinct recordings: :mod:`~excite_cli.identification.choice.selection`), it then adds back the
friction a real joint most likely has (:data:`LIKELY_FRICTION`) where the folds left it out but its
estimate is clear of zero (a loaded joint's viscous friction under noise growing with the torque:
the folds' spread hides what the estimate shows), the clearest first, and removes the added terms
whose estimate is not clear of zero, the least clear first, each a step
(:mod:`~excite_cli.identification.choice.estimates`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from excite_cli.identification.choice.admission import (
    FAMILY_FOLDS,
    Admission,
    Family,
    as_percent,
    effect_count,
    effect_weights,
    family_critical,
    model_size,
    paired_gain,
    passes,
    priced_objective,
)
from excite_cli.identification.choice.crossval import CrossValidation
from excite_cli.identification.choice.estimates import CLEAR
from excite_cli.identification.choice.search_record import Refused, Search, Step
from excite_cli.identification.config import IdentificationConfig
from excite_cli.identification.effects import Term

#: The friction a real joint most likely has: the searches' starts (selection's ``STARTS``), and what a
#: search's end gets back where its estimate is clear of zero (:meth:`StepwiseSearch._restore`).
LIKELY_FRICTION = ("coulomb", "viscous")


class StepwiseSearch:
    """The moves and the objective J of one selection problem under ``rule`` (module docstring)."""

    def __init__(
        self,
        cv: CrossValidation,
        candidates: list[Term],
        declared: list[Term],
        cfg: IdentificationConfig,
        rule: Admission = Admission.PRICED,
        say: Callable[[str], None] | None = None,
        clear: Callable[[list[Term], list[Term]], dict[Term, float]] | None = None,
    ):
        self.cv, self.candidates, self.declared, self.cfg, self.rule = cv, candidates, declared, cfg, rule
        self.clear = clear  # (model, its removable terms) -> each one's |value| / std in the reported fit
        self.say = say  # told each step: the search, the model's size and CV, the moves to score
        self.fixed = {t.family for t in declared}  # declared: never removed (their shape may move)
        self.penalty = np.log1p(cfg.min_improvement)
        self.cache: dict[frozenset, tuple[float, np.ndarray]] = {}

    def score(self, terms: list[Term]) -> tuple[float, np.ndarray]:
        """CV(M) [%] and the (K,) fold errors [%] of the model [Y_B, ``terms``]."""
        key = frozenset(terms)
        if key not in self.cache:
            cv, _, folds = self.cv.score(terms)
            self.cache[key] = (cv, folds)
        return self.cache[key]

    def objective(self, terms: list[Term], score: tuple[float, np.ndarray]) -> float:
        """J of the model ``terms`` with its ``score`` (module docstring)."""
        if self.rule is Admission.PAIRED:
            return float(np.log(np.maximum(score[1], 1e-12)).mean())
        p = effect_count(terms, len(self.declared), effect_weights(self.cfg))
        return float(priced_objective(score[0], p, self.cfg.min_improvement))

    def cost(self, move: str, terms: list[Term], score: tuple[float, np.ndarray]) -> float:
        """J of the model a move leads to; under the price a shape change pays an effect's price as well."""
        shape_price = self.penalty if move == "shape" and self.rule is Admission.PRICED else 0.0
        return self.objective(terms, score) + shape_price

    def allowed(self, move: str, before: tuple[float, np.ndarray], after: tuple[float, np.ndarray]) -> bool:
        """Whether a move from the model scored ``before`` to one scored ``after`` is allowed:
        under the paired test, an addition or shape change that passes it, or the removal of a term
        whose keeping no longer passes it; under the price every move (the best one's cost is then
        compared with J; module docstring)."""
        if self.rule is Admission.PRICED:
            return True  # the price is in the cost; the best move is then compared with J
        return not passes(after[1], before[1]) if move == "remove" else passes(before[1], after[1])

    def gate(self, before: tuple[float, np.ndarray], tried: list) -> tuple[bool, Family | None]:
        """Whether the additions and shape changes ``tried`` from the model scored ``before`` may be
        taken at all: from :data:`~excite_cli.identification.choice.admission.FAMILY_FOLDS` folds on,
        only when one of them passes tested together with the others
        (:func:`~excite_cli.identification.choice.admission.family_critical`); always under the price.
        Also returns the family test (None when there is none). Every move scored is in the family,
        those leading to a model visited before included: the test counts what was tried."""
        if self.rule is Admission.PRICED:
            return True, None
        folds = [m[3][1] for m in tried if m[0] != "remove"]
        family = family_critical(before[1], np.array(folds) if folds else np.zeros((0, before[1].size)))
        return family is None or any(passes(before[1], f, family) for f in folds), family

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

    def _stop(self, terms: list[Term]) -> str:
        """Why the search stops at ``terms`` (no move allowed)."""
        if len(terms) - len(self.declared) >= self.cfg.max_effects:
            return f"max_effects ({self.cfg.max_effects}) reached; no removal or shape change helps"
        if self.rule is Admission.PAIRED:
            return (
                "no addition or shape change improves the folds by more than their own spread (paired test "
                f"over distinct recordings, 95 %, the step's moves together from {FAMILY_FOLDS} folds on) and every "
                "added term passes it"
            )
        return (
            f"no addition, removal or shape change lowers the cross-validated error by "
            f"min_improvement ({100 * self.cfg.min_improvement:g} %)"
        )

    def _refused(self, before: tuple[float, np.ndarray], tried: list, visited: set, family: Family) -> Refused | None:
        """The addition or shape change of lowest J that passed its own test at a step the family test
        kept closed (None when none did)."""
        alone = [
            m for m in tried if m[0] != "remove" and frozenset(m[2]) not in visited and self.allowed(m[0], before, m[3])
        ]
        if not alone:
            return None
        move, term, _, value = min(alone, key=lambda m: self.cost(m[0], m[2], m[3]))
        gain, margin = paired_gain(before[1], value[1])
        together = paired_gain(before[1], value[1], family)[1]
        family_size = sum(m[0] != "remove" for m in tried)
        return Refused(move, term, as_percent(gain), as_percent(margin), as_percent(together), family_size)

    def _taken(self, allowed: list) -> tuple | None:
        """The move a step takes of the ``allowed`` ones (module docstring): under the price the lowest
        cost; under the paired test the smallest model after the move
        (:func:`~excite_cli.identification.choice.admission.model_size`; of one size the lowest J)
        unless a larger one passes the test against it, tested together with every larger move (from
        :data:`~excite_cli.identification.choice.admission.FAMILY_FOLDS` folds on: the best of a grid
        of shape velocities is a selection too); then the same from the larger one taken."""
        if self.rule is Admission.PRICED or not allowed:
            return min(allowed, key=lambda m: self.cost(m[0], m[2], m[3]), default=None)
        order = sorted(allowed, key=lambda m: (model_size(m[2]), self.cost(m[0], m[2], m[3])))
        kept = order[0]
        while True:
            larger = [m for m in order if model_size(m[2]) > model_size(kept[2])]
            family = family_critical(kept[3][1], np.array([m[3][1] for m in larger])) if larger else None
            passing = [m for m in larger if passes(kept[3][1], m[3][1], family)]
            if not passing:
                return kept
            kept = passing[0]  # the smallest of them, of one size the lowest J (the order)

    def run(self, name: str, start: list[Term]) -> Search:
        """The search named ``name`` from the model ``start`` until no move is allowed (module docstring)."""
        terms = list(start)
        score, visited = self.score(terms), {frozenset(start)}
        search = Search(name, list(terms), score[0], terms, score[0], self.objective(terms, score))
        search.initial_folds = score[1]
        while True:
            moves = self.moves(terms)
            if self.say:
                self.say(
                    f"effect search '{name}': step {len(search.steps) + 1}, {len(terms)} terms, CV {score[0]:.2f} %, "
                    f"scoring {len(moves)} moves on {self.cv.folds} folds"
                )
            tried = [(move, term, after, self.score(after)) for move, term, after in moves]
            if not tried:
                search.stop = "no move left (every candidate is in the model)"
                break
            gate, family = self.gate(score, tried)
            allowed = [
                m
                for m in tried
                if (gate or m[0] == "remove") and self.allowed(m[0], score, m[3]) and frozenset(m[2]) not in visited
            ]
            best = self._taken(allowed)
            priced_out = self.rule is Admission.PRICED and best is not None
            if best is None or (priced_out and self.cost(best[0], best[2], best[3]) >= search.objective - 1e-12):
                search.stop = self._stop(terms)
                search.refused = None if gate else self._refused(score, tried, visited, family)
                break
            move, term, after, value = best
            gain, margin = paired_gain(score[1], value[1]) if self.rule is Admission.PAIRED else (np.nan, np.nan)
            tested = family is not None and move != "remove"  # removals keep the plain test
            together = paired_gain(score[1], value[1], family)[1] if tested else np.nan
            tried_cv = [(m, t, v[0]) for m, t, _, v in tried]
            search.steps.append(
                Step(
                    move,
                    term,
                    after,
                    value[0],
                    score[0],
                    tried_cv,
                    as_percent(gain),
                    as_percent(margin),
                    as_percent(together),
                )
            )
            terms, score = after, value
            visited.add(frozenset(terms))
            search.objective = self.objective(terms, score)
        terms, score = self._clear_of_zero(search, *self._restore(search, terms, score))
        search.terms, search.cv_error, search.folds = terms, score[0], score[1]
        return search

    def _removable(self, terms: list[Term]) -> list[Term]:
        """The terms of ``terms`` a removal may take: added, and no other term requires them."""
        return [m[1] for m in self.moves(terms) if m[0] == "remove"]

    def _by_estimate(
        self, search: Search, move: str, term: Term, after: list[Term], before: tuple, ratio: float
    ) -> tuple[list[Term], tuple]:
        """``after`` and its score, the ``move`` of ``term`` from the model scored ``before`` a step of
        ``search`` judged by the term's estimate (``ratio`` standard deviations from zero), not the folds."""
        value = self.score(after)
        search.steps.append(Step(move, term, after, value[0], before[0], [], clear_of_zero=ratio))
        search.objective = self.objective(after, value)
        return after, value

    def _restore(self, search: Search, terms: list[Term], score: tuple) -> tuple[list[Term], tuple]:
        """The end ``terms`` (scored ``score``) with the friction a real joint most likely has
        (:data:`LIKELY_FRICTION`) added back where the search left it out and its estimate, added to the
        end, is clear of zero (:data:`~excite_cli.identification.choice.estimates.CLEAR`), the clearest
        first and the rest judged again with it, each addition a step of ``search``."""
        restored = 0
        likely = [c for c in self.candidates if c.effect in LIKELY_FRICTION and c.shape is None and c.coupling is None]
        while self.clear is not None:
            held = {t.family for t in terms}
            ratios = {c: self.clear(terms + [c], [c])[c] for c in likely if c.family not in held}
            term, ratio = max(ratios.items(), key=lambda item: item[1], default=(None, 0.0))
            if ratio < CLEAR:
                break
            terms, score = self._by_estimate(search, "add", term, terms + [term], score, ratio)
            restored += 1
        if restored:
            search.stop += (
                f"; then {restored} friction term{'s' * (restored > 1)} the folds left out added back, whose "
                f"estimate the report tells from zero ({CLEAR:g} standard deviations or more)"
            )
        return terms, score

    def _clear_of_zero(self, search: Search, terms: list[Term], score: tuple) -> tuple[list[Term], tuple]:
        """The end ``terms`` (scored ``score``) without the added terms whose estimate is not clear of
        zero (:data:`~excite_cli.identification.choice.estimates.CLEAR`), the least clear removed first
        and the rest judged again without it, each removal a step of ``search``."""
        removed = 0
        while self.clear is not None and (removable := self._removable(terms)):
            term, ratio = min(self.clear(terms, removable).items(), key=lambda item: item[1])
            if ratio >= CLEAR:
                break
            terms, score = self._by_estimate(search, "remove", term, [t for t in terms if t != term], score, ratio)
            removed += 1
        if removed:
            search.stop += (
                f"; then {removed} added term{'s' * (removed > 1)} removed whose estimate the report could not tell "
                f"from zero (under {CLEAR:g} standard deviations)"
            )
        return terms, score
