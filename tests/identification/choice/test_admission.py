"""The paired test over folds against scipy's paired t-test, the family-wise error of the moves of one
step tested together on draws with no gain, and the fit choice it makes."""

import zlib

import numpy as np
import pytest
import scipy.stats

from excite_cli.identification.choice.admission import (
    FAMILY_FOLDS,
    PAIRED_FOLDS,
    Admission,
    admission_of,
    as_percent,
    family_critical,
    paired_choice,
    paired_gain,
    passes,
    simplest,
)
from excite_cli.identification.choice.estimates import CLEAR
from excite_cli.identification.choice.search import StepwiseSearch
from excite_cli.identification.config import IdentificationConfig
from excite_cli.identification.effects import Term


@pytest.mark.parametrize("seed", range(20))
def test_the_margin_is_scipys_one_sided_paired_t_test_at_95_percent(seed):
    rng = np.random.default_rng(seed)
    before = rng.uniform(2.0, 5.0, 5)
    after = before * np.exp(-rng.normal(0.01, 0.02, 5))
    mean, margin = paired_gain(before, after)
    p = scipy.stats.ttest_rel(np.log(before), np.log(after), alternative="greater").pvalue
    assert mean == pytest.approx(np.mean(np.log(before / after)))
    assert (mean > margin) == (p < 0.05)


def test_a_gain_every_fold_shares_passes_however_small_and_a_cut_is_a_percentage():
    before = np.array([3.0, 4.0, 5.0, 6.0])
    mean, margin = paired_gain(before, before * 0.99)
    assert margin == pytest.approx(0.0, abs=1e-12) and as_percent(mean) == pytest.approx(1.0)
    assert passes(before, before * 0.99) and not passes(before, before * (1 - 1e-6))  # the floor: 0.1 %


def test_only_three_or_more_recording_folds_are_judged_by_the_paired_test():
    assert admission_of(True, PAIRED_FOLDS) is Admission.PAIRED
    assert admission_of(True, PAIRED_FOLDS - 1) is Admission.PRICED
    assert admission_of(False, 10) is Admission.PRICED


def test_least_squares_is_chosen_only_where_every_fold_agrees_it_is_better():
    consistent = np.array([4.0, 5.0, 6.0, 5.0])
    folds = np.stack([np.stack([consistent * 0.9, consistent])])  # (1 model, 2 fits: LS, consistent, 4 folds)
    J = np.log(folds).mean(axis=2)
    assert paired_choice(J, folds, [False, True], np.zeros((1, 2))) == (
        0,
        0,
    )  # 10 % better on every fold: least squares
    mixed = folds.copy()
    mixed[0, 0] = consistent * np.array([0.5, 1.3, 0.8, 1.3])  # better on average, worse on two folds
    J = np.log(mixed).mean(axis=2)
    assert J[0, 0] < J[0, 1] and paired_choice(J, mixed, [False, True], np.zeros((1, 2))) == (0, 1)


def test_a_larger_model_is_kept_only_when_it_passes_the_test_against_the_smaller():
    small = np.array([4.0, 5.0, 6.0, 5.0])
    noisy = small * np.array([0.9, 1.08, 0.95, 1.0])  # lower on average, folds disagree
    consistent = small * 0.97  # 3 % lower on every fold
    for larger, kept in ((noisy, 0), (consistent, 1)):
        folds = np.stack([small, larger])[:, None, :]  # (2 models, 1 fit, 4 folds)
        J = np.log(folds).mean(axis=2)
        assert simplest(J, folds, np.array([[0], [3]]), [0]) == (kept, 0)
    folds = np.stack([consistent, small])[:, None, :]  # the larger model listed first: sizes order them
    assert simplest(np.log(folds).mean(axis=2), folds, np.array([[3], [0]]), [0]) == (0, 0)


def _step(rng, folds: int, moves: int, gain: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Fold errors of a model and of ``moves`` moves from it: no move helps (each fold's change is
    symmetric about 0, the moves' changes correlated through a share of each fold's), the first one
    by ``gain`` [log units] on every fold."""
    before = rng.uniform(2.0, 5.0, folds)
    common = rng.normal(0.0, 0.02, folds)
    change = 0.8 * common + 0.6 * rng.normal(0.0, 0.02, (moves, folds))
    change[0] += gain
    return before, before * np.exp(-change)


@pytest.mark.parametrize("folds", [FAMILY_FOLDS, 8, 10])
def test_the_moves_of_a_step_tested_together_admit_none_of_many_useless_ones_in_95_percent(folds):
    """400 steps of 60 moves none of which helps: some move passes at the family's critical t in at
    most 5 % of them (binomial: ≤ 8 % allowing for the draws), where each move's own t-test passes some
    move in most steps; a move that gains 3 % on every fold still passes."""
    rng = np.random.default_rng(folds)
    family = alone = 0
    for _ in range(400):
        before, after = _step(rng, folds, 60)
        c = family_critical(before, after)
        family += any(passes(before, a, c) for a in after)
        alone += any(passes(before, a) for a in after)
    assert family <= 0.08 * 400 and alone >= 0.3 * 400, (family, alone)
    before, after = _step(rng, folds, 60, gain=0.1)
    assert passes(before, after[0], family_critical(before, after))


def test_below_five_folds_each_move_is_tested_alone():
    """16 sign patterns of 4 folds cannot put a share under 5 %: no family critical t."""
    before, after = _step(np.random.default_rng(0), PAIRED_FOLDS, 10)
    assert family_critical(before, after) is None


class _Folds:
    """A stand-in for the cross-validation (its ``score``): a model's fold errors are the start's
    times exp(−Σ its terms' true ``gains``) and a change of its own drawn as in :func:`_step` (seeded by
    the model), so that only ``gains`` help."""

    def __init__(self, folds: int, gains: dict, seed: int):
        self.folds, self.gains, self.seed = folds, gains, seed
        self.common = np.random.default_rng(seed).normal(0.0, 0.02, folds)
        self.before = np.random.default_rng(seed + 1).uniform(2.0, 5.0, folds)

    def score(self, terms):
        key = zlib.crc32(repr(sorted(terms, key=repr)).encode())
        own = np.random.default_rng([self.seed, key]).normal(0.0, 0.02, self.folds) if terms else 0.0
        change = sum(self.gains.get(t, 0.0) for t in terms) + (0.8 * self.common + 0.6 * own) * bool(terms)
        errors = self.before * np.exp(-change)
        return float(errors.mean()), None, errors


def _search(folds: int, gains: dict, seed: int, candidates=None, declared=()):
    candidates = candidates or [Term("coulomb", j) for j in range(60)]
    cfg = IdentificationConfig(candidates=["coulomb", "viscous", "stribeck"])
    search = StepwiseSearch(_Folds(folds, gains, seed), candidates, list(declared), cfg, Admission.PAIRED)
    return search.run("none", list(declared))


def test_a_step_records_its_family_margin_and_a_stop_names_the_move_the_family_refused():
    """From 5 folds on a step taken records the margin its move had tested with the others (larger
    than its own: 60 moves); where the family kept the last step closed while some move passed its
    own test, the search names that move with a gain between its own margin and the family's."""
    search = _search(8, {Term("coulomb", 7): 0.1}, 0)
    first = search.steps[0]
    assert first.term == Term("coulomb", 7) and first.fold_gain > first.family_margin > first.fold_margin
    refused = [s.refused for s in (_search(8, {}, seed) for seed in range(10)) if s.refused is not None]
    assert refused, "no step where a useless move passed its own test in 10 draws"
    for r in refused:
        assert r.margin < r.gain <= r.family_margin and r.tried == 60 and r.move == "add"
        assert "tested together" in r.label([f"j{k}" for k in range(60)])
    assert np.isnan(_search(PAIRED_FOLDS, {Term("coulomb", 7): 0.1}, 0).steps[0].family_margin)


def test_a_step_takes_a_shaped_term_over_a_plain_one_only_where_it_passes_the_test_against_it():
    """Coulomb friction declared; viscous friction and a Stribeck term (a shape velocity more) help
    alike, among 58 useless moves: the viscous term is taken in at least 9 of 10 draws (by the lower J
    alone about half would be the Stribeck term's); a Stribeck term 5 % better than viscous on every
    fold is taken."""
    viscous, stribeck = Term("viscous", 1), Term("stribeck", 1, 0.5)
    candidates = [viscous, stribeck, Term("stribeck", 1, 0.1)] + [Term("viscous", j) for j in range(2, 59)]
    declared = [Term("coulomb", 1)]
    taken = [
        _search(8, {viscous: 0.05, stribeck: 0.05}, seed, candidates, declared).steps[0].term for seed in range(10)
    ]
    assert taken.count(viscous) >= 9, taken
    better = _search(8, {viscous: 0.05, stribeck: 0.1}, 0, candidates, declared)
    assert better.steps[0].term == stribeck


class _Clear:
    """A stand-in of the reported fit's ratios: each term's from ``ratios`` (``other`` for any other),
    and the terms it was asked about."""

    def __init__(self, ratios: dict, other: float = 10.0):
        self.ratios, self.other, self.asked = ratios, other, []

    def __call__(self, terms, asked):
        self.asked.append(list(asked))
        return {t: self.ratios.get(t, self.other) for t in asked}


def test_the_search_removes_the_admitted_terms_its_estimates_cannot_tell_from_zero_least_clear_first():
    """Eight folds where two terms help: both admitted; stated 1.5 and 2.5 std from zero they are
    removed (1.5 first), each a step of the search with its ratio; at 3.5 the term stays; the
    declared term is never asked about."""
    declared, a, b = [Term("viscous", 99)], Term("coulomb", 3), Term("coulomb", 7)
    candidates = [Term("coulomb", j) for j in range(20)]
    cfg = IdentificationConfig(candidates=["coulomb", "viscous"])
    gains = {a: 0.1, b: 0.1}
    plain = StepwiseSearch(_Folds(8, gains, 0), candidates, declared, cfg, Admission.PAIRED).run("s", declared)
    assert {a, b} <= set(plain.terms)
    clear = _Clear({a: 2.5, b: 1.5}, other=0.0)
    search = StepwiseSearch(_Folds(8, gains, 0), candidates, declared, cfg, Admission.PAIRED, clear=clear).run(
        "s", declared
    )
    removals = [s for s in search.steps if not np.isnan(s.clear_of_zero)]
    assert [(s.move, s.term, s.clear_of_zero) for s in removals] == [("remove", b, 1.5), ("remove", a, 2.5)]
    assert a not in search.terms and b not in search.terms and search.terms == removals[-1].terms
    assert "2 added terms removed" in search.stop and f"under {CLEAR:g} standard deviations" in search.stop
    assert all(declared[0] not in asked for asked in clear.asked)
    kept = StepwiseSearch(
        _Folds(8, gains, 0), candidates, declared, cfg, Admission.PAIRED, clear=_Clear({a: 3.5}, other=0.0)
    )
    assert a in kept.run("s", declared).terms


def test_a_search_end_gets_back_the_likely_friction_its_estimates_tell_from_zero_clearest_first():
    """Eight folds where only Coulomb friction on joint 3 helps: the search leaves out viscous friction
    on joints 5 and 6 (the folds cannot show it), whose estimates added to the end stand 5 and 4 std
    from zero: both are added back after the search (5 first), each a step with its ratio, and judged
    again; at 2.9 std, or a Stribeck term however clear (not the friction a joint most likely has), none."""
    a, v5, v6, stribeck = Term("coulomb", 3), Term("viscous", 5), Term("viscous", 6), Term("stribeck", 7, 0.1)
    candidates = [Term("coulomb", j) for j in range(20)] + [v5, v6, stribeck]
    cfg = IdentificationConfig(candidates=["coulomb", "viscous", "stribeck"])

    def run(ratios):
        clear = _Clear({a: 50.0, **ratios}, other=0.0)
        return StepwiseSearch(_Folds(8, {a: 0.1}, 0), candidates, [], cfg, Admission.PAIRED, clear=clear).run("s", [])

    search = run({v5: 5.0, v6: 4.0, stribeck: 20.0})
    back = [s for s in search.steps if s.move == "add" and not np.isnan(s.clear_of_zero)]
    assert [(s.term, s.clear_of_zero) for s in back] == [(v5, 5.0), (v6, 4.0)]
    assert set(search.terms) == {a, v5, v6} and "2 friction terms the folds left out added back" in search.stop
    assert set(run({v5: 2.9, stribeck: 20.0}).terms) == {a}
