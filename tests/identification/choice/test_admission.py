"""The paired test over folds against scipy's paired t-test, and the fit choice it makes."""

import numpy as np
import pytest
import scipy.stats

from excite_cli.identification.choice.admission import (
    PAIRED_FOLDS,
    Admission,
    admission_of,
    as_percent,
    paired_choice,
    paired_gain,
    passes,
    simplest,
)


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
