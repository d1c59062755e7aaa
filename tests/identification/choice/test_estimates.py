"""The ratio that keeps a term only when its estimate is clear of zero in the reported fit: its
clearest coefficient over the larger of the two reported standard deviations (the search's removals
by it: tests/identification/choice/test_admission.py; a small true effect it keeps:
test_crossval_selection.py)."""

import numpy as np
import pytest

from excite_cli.identification.choice.estimates import clearance
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.least_squares import Fit


def test_a_terms_ratio_is_its_clearest_coefficient_over_the_larger_of_its_two_deviations():
    """Two base parameters, then a one-coefficient term and a three-coefficient one (per-run offsets):
    the larger deviation counts (without the spread, as on four recordings, the noise's), a spread the
    data cannot give (NaN) leaves the noise's, a coefficient held at its bound 0 counts as 0."""
    one, runs = Term("viscous", 0), Term("offset", 1)
    fit = Fit(
        x=np.array([5.0, 5.0, 0.6, 0.0, -0.9, 0.2]),
        std=np.array([1.0, 1.0, 0.1, 0.1, 0.1, 0.1]),
        sigma=np.ones(2),
        between=np.array([1.0, 1.0, 0.2, np.nan, np.nan, 0.4]),
    )
    ratios = clearance(fit, [one, runs], {one: 1, runs: 3})
    assert ratios == pytest.approx({one: 3.0, runs: 9.0})
    assert clearance(fit, [one, runs], {one: 1, runs: 3}, spread=False) == pytest.approx({one: 6.0, runs: 9.0})
    assert clearance(Fit(np.array([1.0, 0.0]), np.array([0.1, np.nan]), np.ones(1)), [one], {one: 1}) == {one: 0.0}
