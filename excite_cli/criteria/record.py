"""One criterion of the stacked base regressor C, as one record: its name, what it rewards, and its
value and gradient with respect to C from the eigenvalues of CᵀC.

Every criterion here is a function of the eigenvalues λ of the information matrix CᵀC, and its
gradient in C has the form Σ_r a_r (C v_r) v_rᵀ over eigenvectors v_r (Eq. 17 for the condition number;
its D-, E- and A-optimal analogues), so a record gives the value, the indices r it needs and the
coefficients a_r; :class:`~excite_cli.design.criterion.Criterion` turns them into the gradient in
the Fourier coefficients. numpy is handed to the formula, so the command line can list the records'
names without loading it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

#: σ_min is floored at this fraction of σ_max, so rank loss gives a large finite value, never NaN.
RANK_FLOOR = 1e-14

#: (λ floored (b,) ascending, numpy) → (value, indices r (R,), coefficients a_r (R,)).
Formula = Callable[[Any, Any], tuple[float, Any, Any]]


@dataclass(frozen=True)
class CriterionRecord:
    """One criterion of ``optimizer.objective``, everything about it in one record.

    Attributes:
        name: the name configs, tables and HDF5 files use.
        rewards: what a lower value rewards, in one line (the documentation and ``--help`` say it).
        formula: the value and gradient terms from the floored eigenvalues (module docstring).
        shown_as: the figure tables show for it: ``cond`` (the condition number, the value
            exponentiated when it is a log) or the criterion's own value.
        exponentiate: tables show exp(value) (a log criterion shown as the condition number).
        source: where it comes from.
        extremes: for a criterion of the extreme singular values only, non-smooth where one is
            multiple: (w_max, w_min) with f = w_max log σ_max + w_min log σ_min (or exp of that with
            ``exponentiate_extremes``); () for a smooth criterion. The stationarity test of
            :mod:`~excite_cli.search.kkt` uses it.
        exponentiate_extremes: f = exp(w_max log σ_max + w_min log σ_min) (cond itself).
        scaling: the regressor it is taken of unless ``optimizer.scaling`` says: ``none`` (C, the
            paper's) or ``urdf`` (C L, the frame in which it measures what it is meant to).
        hedged: where a config declares no noise, the design weighs the rows by the hedge
            (:func:`~excite_cli.design.noise.hedged_noise`): a criterion of the estimate's covariance
            (A-, D-, E-optimality) needs a noise model; the paper's condition number (off) is of the
            rows as they are.
    """

    name: str
    rewards: str
    formula: Formula
    shown_as: str = ""
    exponentiate: bool = False
    source: str = ""
    extremes: tuple[float, ...] = ()
    exponentiate_extremes: bool = False
    scaling: str = "none"
    hedged: bool = True

    def terms(self, eigenvalues: Any) -> tuple[float, Any, Any]:
        """The value, the indices r (R,) of the eigenpairs the gradient needs and their coefficients
        a_r (R,), from the eigenvalues λ (b,) of CᵀC in ascending order; λ_min is floored at
        (``RANK_FLOOR`` σ_max)², so rank loss gives a large finite value and finite coefficients."""
        import numpy as np

        lam = np.maximum(eigenvalues, (RANK_FLOOR**2) * max(eigenvalues[-1], 0.0))
        return self.formula(np.maximum(lam, np.finfo(float).tiny), np)

    def shown(self, value: float) -> float:
        """The figure tables and progress lines show for ``value``."""
        import math

        return math.exp(value) if self.exponentiate else value

    @property
    def weighed_extremes(self) -> list[tuple[int, float]]:
        """(side, w) of each extreme of ``extremes`` with a non-zero weight: side 0 the largest singular
        value (w_max), 1 the smallest (w_min); empty for a smooth criterion."""
        return [(side, weight) for side, weight in enumerate(self.extremes) if weight]

    @property
    def label(self) -> str:
        """The name tables put above that figure."""
        return self.shown_as or self.name
