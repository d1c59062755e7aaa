"""The criteria of ``optimizer.objective``: each one :class:`~excite_cli.criteria.record.CriterionRecord`,
so adding a criterion is adding a record to ``CRITERIA`` (its name, what it rewards, its formula).

- ``cond``, ``log_cond``: the condition number σ_max/σ_min of C (Eq. 5) or its log (Eq. 17's gradient);
- ``log_det``: D-optimality, −log det(CᵀC)/b, the mean log eigenvalue of the information matrix
  maximized (the paper's ref. [20]);
- ``sigma_min``: E-optimality, −log σ_min(C), the worst determined direction's excitation maximized;
- ``log_trace_inverse``: A-optimality, ½ log(tr((CᵀC)⁻¹)/b), the log of the RMS of 1/σ_i, least squares'
  RMS parameter error per unit of torque noise (Pukelsheim, Optimal Design of Experiments, 1993).
"""

from __future__ import annotations

from excite_cli.criteria.record import CriterionRecord
from excite_cli.errors import ExciteError


def _condition(lam, np, log: bool):
    s_max, s_min = np.sqrt(lam[-1]), np.sqrt(lam[0])
    c = s_max / s_min
    coefficients = np.array([1.0 / (s_min * s_max), -s_max / s_min**3])
    indices = np.array([lam.size - 1, 0])
    return (float(np.log(c)), indices, coefficients / c) if log else (float(c), indices, coefficients)


def _log_trace_inverse(lam, np):
    inverse = 1.0 / lam
    return float(0.5 * np.log(inverse.mean())), np.arange(lam.size), -(inverse**2) / inverse.sum()


#: Every criterion, by name, in the order help texts and ``verify-gradient`` list them.
CRITERIA = {
    c.name: c
    for c in (
        CriterionRecord(
            "cond",
            "a small ratio of the best to the worst excited direction",
            lambda lam, np: _condition(lam, np, log=False),
            shown_as="cond",
            source="Eq. 5",
            extremes=(1.0, -1.0),
            exponentiate_extremes=True,
            hedged=False,
        ),
        CriterionRecord(
            "log_cond",
            "the same ratio, on a log scale (the paper's criterion)",
            lambda lam, np: _condition(lam, np, log=True),
            shown_as="cond",
            exponentiate=True,
            source="Eqs. 5, 17",
            extremes=(1.0, -1.0),
            hedged=False,
        ),
        CriterionRecord(
            "log_det",
            "a large volume of the information matrix: every direction excited, on average",
            lambda lam, np: (float(-np.log(lam).sum() / lam.size), np.arange(lam.size), -2.0 / (lam.size * lam)),
            source="D-optimality, the paper's ref. [20]",
        ),
        CriterionRecord(
            "sigma_min",
            "a large excitation of the worst excited direction",
            lambda lam, np: (float(-0.5 * np.log(lam[0])), np.array([0]), np.array([-1.0 / lam[0]])),
            source="E-optimality, the paper's ref. [20]",
            extremes=(0.0, -1.0),
        ),
        CriterionRecord(
            "log_trace_inverse",
            "a small RMS parameter error of least squares per unit of torque noise",
            _log_trace_inverse,
            source="A-optimality (Pukelsheim 1993)",
            scaling="urdf",  # of C L: the RMS error of parameters in the units the URDF gives them
        ),
    )
}

#: Their names (``optimizer.objective``'s choices).
NAMES = tuple(CRITERIA)


def criterion_record(name: str) -> CriterionRecord:
    """The record of the criterion ``name``.

    Raises:
        ExciteError: no criterion has that name (under ``optimizer.objective``).
    """
    if name not in CRITERIA:
        raise ExciteError("optimizer.objective", f"unknown '{name}', expected one of {', '.join(NAMES)}")
    return CRITERIA[name]
