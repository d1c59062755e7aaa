"""A criterion record's terms: rank loss floored to finite values, and what tables show."""

import math

import numpy as np
import pytest

from excite_cli.criteria.catalogue import CRITERIA
from excite_cli.criteria.record import RANK_FLOOR, CriterionRecord


@pytest.mark.parametrize(
    "objective, expected", [("cond", 1e14), ("log_cond", np.log(1e14)), ("sigma_min", -np.log(2e-14))]
)
def test_rank_loss_is_floored_to_finite_values_and_gradient_weights(objective, expected):
    """σ_min = 0 (λ = 0 of CᵀC): σ_min is floored at 1e-14 σ_max = 2e-14, so value and the gradient's
    coefficients a_r are finite."""
    assert RANK_FLOOR == 1e-14
    value, used, coefficients = CRITERIA[objective].terms(np.array([0.0, 1.0, 4.0]))
    assert value == pytest.approx(expected, rel=1e-12)
    assert np.all(np.isfinite(coefficients)) and 0 in used


def test_a_log_criterion_is_shown_as_its_condition_number():
    assert CRITERIA["log_cond"].shown(math.log(250.0)) == pytest.approx(250.0)
    assert CRITERIA["log_cond"].label == CRITERIA["cond"].label == "cond"
    assert CRITERIA["log_det"].shown(-3.5) == -3.5 and CRITERIA["log_det"].label == "log_det"


def test_a_new_record_needs_only_its_formula():
    """A toy criterion (−log of the mean eigenvalue) is one record: its formula gives value and gradient terms."""
    mean = CriterionRecord(
        "log_mean",
        "a large mean eigenvalue",
        lambda lam, np: (float(-np.log(lam.mean())), np.arange(lam.size), -2.0 / lam.sum() * np.ones(lam.size)),
    )
    value, used, a = mean.terms(np.array([1.0, 3.0]))
    assert value == pytest.approx(-np.log(2.0)) and list(used) == [0, 1] and a == pytest.approx([-0.5, -0.5])
