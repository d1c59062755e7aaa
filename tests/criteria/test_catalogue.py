"""Every criterion record against independent truth: its value from an SVD of C, and its gradient in C,
Σ_r a_r (C v_r) v_rᵀ from the record's terms, against central finite differences in C."""

import numpy as np
import pytest

from excite_cli.criteria import CRITERIA, NAMES, criterion_record
from excite_cli.errors import ExciteError

SVD_VALUES = {
    "cond": lambda s: s[0] / s[-1],
    "log_cond": lambda s: np.log(s[0] / s[-1]),
    "log_det": lambda s: -np.sum(np.log(s**2)) / s.size,
    "sigma_min": lambda s: -np.log(s[-1]),
    "log_trace_inverse": lambda s: 0.5 * np.log(np.mean(1.0 / s**2)),
}


def _value(record, C):
    return record.terms(np.linalg.eigvalsh(C.T @ C))[0]


@pytest.mark.parametrize("name", NAMES)
def test_value_and_gradient_in_C_match_the_svd_and_finite_differences(name):
    record = criterion_record(name)
    C = np.random.default_rng(3).standard_normal((12, 4)) @ np.diag([1.0, 2.0, 0.5, 3.0])
    assert _value(record, C) == pytest.approx(SVD_VALUES[name](np.linalg.svd(C, compute_uv=False)), rel=1e-10)
    lam, V = np.linalg.eigh(C.T @ C)
    _, used, a = record.terms(lam)
    analytic = sum(a_r * np.outer(C @ V[:, r], V[:, r]) for r, a_r in zip(used, a))
    step, fd = 1e-6, np.zeros_like(C)
    for index in np.ndindex(C.shape):
        E = np.zeros_like(C)
        E[index] = step
        fd[index] = (_value(record, C + E) - _value(record, C - E)) / (2 * step)
    assert np.abs(analytic - fd).max() <= 1e-6 * np.abs(fd).max()


def test_names_are_declared_once_in_the_records():
    assert NAMES == tuple(CRITERIA) and all(CRITERIA[n].name == n for n in NAMES)
    assert all(CRITERIA[n].rewards for n in NAMES)


def test_an_unknown_criterion_names_the_field_and_the_choices():
    with pytest.raises(ExciteError, match=r"optimizer\.objective.*unknown 'cond2'.*log_det"):
        criterion_record("cond2")
