"""Analytic gradient against finite differences: error and speed (the paper's check in Section IV-B)."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from excite_cli.constraints import Constraint
from excite_cli.design.criterion import Criterion


@dataclass(frozen=True)
class GradientCheck:
    """Comparison of ∂c/∂α (Eq. 49) with finite differences at one α.

    Attributes:
        variables: number of Fourier coefficients.
        value: the criterion there.
        error_central: ‖g − g_cd‖ / ‖g_cd‖ against central differences.
        error_forward: ‖g − g_fd‖ / ‖g_fd‖ against one-sided differences (the paper's 1.3e-5).
        analytic_s: wall time of one analytic gradient [s] (median of repeats).
        forward_s: wall time of one one-sided finite-difference gradient [s].
    """

    variables: int
    value: float
    error_central: float
    error_forward: float
    analytic_s: float
    forward_s: float

    @property
    def speedup(self) -> float:
        """forward_s / analytic_s."""
        return self.forward_s / self.analytic_s


def finite_difference_gradient(criterion: Criterion, alpha: np.ndarray, step: float, central: bool) -> np.ndarray:
    """Finite-difference gradient (n, 2N+1) of the criterion, step [rad] on each coefficient."""
    grad = np.zeros_like(alpha)
    f0 = None if central else criterion.value(alpha)
    for index in np.ndindex(alpha.shape):
        plus = alpha.copy()
        plus[index] += step
        if central:
            minus = alpha.copy()
            minus[index] -= step
            grad[index] = (criterion.value(plus) - criterion.value(minus)) / (2 * step)
        else:
            grad[index] = (criterion.value(plus) - f0) / step
    return grad


def check_gradient(criterion: Criterion, alpha: np.ndarray, step: float = 1e-6, repeats: int = 30) -> GradientCheck:
    """Compare the analytic gradient with central and one-sided differences of step ``step``.

    Args:
        criterion: the criterion (cond or log cond, with its C₀).
        alpha: (n, 2N+1) Fourier coefficients.
        step: finite-difference step (the paper used 1e-6).
        repeats: analytic gradients timed; their median is reported (robust to a busy machine).

    Both are timed with one BLAS thread, as the optimizer runs (:mod:`excite_cli.search.engine`).
    """
    with threadpool_limits(limits=1):
        criterion.value_and_gradient(alpha)  # first call makes the model copies
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            value, analytic = criterion.value_and_gradient(alpha)
            times.append(time.perf_counter() - start)
        analytic_s = float(np.median(times))
        start = time.perf_counter()
        forward = finite_difference_gradient(criterion, alpha, step, central=False)
        forward_s = time.perf_counter() - start
        central = finite_difference_gradient(criterion, alpha, step, central=True)
    return GradientCheck(
        variables=alpha.size,
        value=value,
        error_central=float(np.linalg.norm(analytic - central) / np.linalg.norm(central)),
        error_forward=float(np.linalg.norm(analytic - forward) / np.linalg.norm(forward)),
        analytic_s=analytic_s,
        forward_s=forward_s,
    )


def constraint_jacobian_error(constraint: Constraint, alpha: np.ndarray, step: float = 1e-7) -> float:
    """‖J − J_cd‖ / ‖J_cd‖ of a constraint's Jacobian against central differences of step ``step``
    on each Fourier coefficient of α (n, 2N+1)."""
    _, J = constraint.evaluate(alpha)
    fd = np.zeros_like(J)
    for k in range(alpha.size):
        e = np.zeros(alpha.size)
        e[k] = step
        plus = constraint.evaluate(alpha + e.reshape(alpha.shape))[0]
        minus = constraint.evaluate(alpha - e.reshape(alpha.shape))[0]
        fd[:, k] = (plus - minus) / (2 * step)
    return float(np.linalg.norm(J - fd) / np.linalg.norm(fd))
