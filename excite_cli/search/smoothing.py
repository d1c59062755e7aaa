"""The smoothed criterion a stalled restart of cond, log cond or E-optimality continues on.

The epigraph form (:class:`~excite_cli.search.nlp.Epigraph`) bounds each extreme singular value by
its own gradient; at a cluster of nearly equal extremes its subproblem never sees the cross terms of
their derivative (Overton 1992), and SLSQP can stall short of Clarke stationarity: the ``excite init``
UR3's E-optimality (seed 0, iteration 1: its four smallest σ within 7e-5 of each other) at a Clarke
residual of 1.5e-3 after 1032 iterations; the G1's cond (seed 1, iteration 1) at 4.9e-3 after 4000.
Such a restart continues from its end point on the log-sum-exp smoothing of its extremes,

    f_μ(z) = Σ_c w_c s_c μ log Σ_{i ∈ B_c} exp(s_c log σ_i(z) / μ),

s_c = +1 at the largest singular values and −1 at the smallest, B_c the singular values within
``BAND`` × μ of extreme c (the others weigh less than e^-30), μ = ``SMOOTHING``. It is a spectral
function, smooth however the singular values cluster (Lewis 1996), the smoothing of λ_max of
Nesterov (Math. Program. 2007); its gradient Σ_c w_c Σ_i p_i ∇log σ_i (p the softmax weights) is,
where the weights outside the Clarke cluster vanish (1 % away: e^-100), an element of Clarke's
subdifferential, so the quasi-Newton matrix of SLSQP sees the curvature the epigraph's linear bounds
hide, and the run stops at the Clarke test of the true criterion (:func:`~excite_cli.search.kkt.until_done`).
The smoothing costs at most μ Σ_c |w_c| log |B_c| of the (log) criterion: f ≤ f_μ ≤ f + that bound,
so an end reached by lowering f_μ from z₀ has f ≤ f(z₀) + the bound at z₀ (:func:`smoothing_bound`).
"""

from __future__ import annotations

import numpy as np
from scipy.special import logsumexp, softmax

from excite_cli.design.criterion import Criterion
from excite_cli.memo import once
from excite_cli.search.nlp import Evaluations, NlpForm

#: μ [1, of log σ]: the smoothing's width, and its largest cost per extreme over log |B_c|.
SMOOTHING = 1e-4
#: B_c: the singular values within this × μ of their extreme (the others weigh less than e^-BAND).
BAND = 30.0


class Smoothed:
    """The problem of ``problem`` (:class:`~excite_cli.search.nlp.Evaluations`) with its criterion of
    the extreme singular values replaced by f_μ (module docstring): value and gradient in z (n_z,),
    the constraints as they are."""

    form = NlpForm.SMOOTHED

    def __init__(self, problem: Evaluations, mu: float = SMOOTHING):
        self.problem, self.mu = problem, mu
        self.constraint_values, self.constraint_jacobian = problem.constraint_values, problem.constraint_jacobian
        self.sides = problem.criterion.objective.weighed_extremes

    def start(self, z: np.ndarray) -> np.ndarray:
        """The solver's variables at z (n_z,): z."""
        return z

    def value(self, z: np.ndarray) -> float:
        """f_μ at z (n_z,) [1, of log σ]."""
        return self._value_and_gradient(z)[0]

    def gradient(self, z: np.ndarray) -> np.ndarray:
        """∇f_μ in z (n_z,): Σ_c w_c Σ_i p_i ∇log σ_i, chained into the optimizer's variables."""
        return self._value_and_gradient(z)[1]

    def _value_and_gradient(self, z: np.ndarray) -> tuple[float, np.ndarray]:
        def compute():
            alpha, criterion = self.problem.boundary.to_alpha(z), self.problem.criterion
            logs = np.log(criterion.floored_singular_values(alpha))
            bands = [(weight, *_band(logs, side, self.mu)) for side, weight in self.sides]
            members = np.concatenate([band for *_, band in bands])  # every extreme's gradients in one call
            gradients = criterion.log_singular_values(alpha, members)[1].reshape(members.size, -1)
            value, gradient, row = 0.0, np.zeros(alpha.size), 0
            for weight, sign, band in bands:
                value += weight * sign * self.mu * logsumexp(sign * logs[band] / self.mu)
                gradient += weight * (softmax(sign * logs[band] / self.mu) @ gradients[row : row + band.size])
                row += band.size
            return float(value), self.problem.boundary.chain(gradient)

        return once(self, "smoothed", z, compute)


def _band(logs: np.ndarray, side: int, mu: float) -> tuple[float, np.ndarray]:
    """s_c and the indices B_c (ascending) of extreme ``side`` (0: largest, 1: smallest) of log σ (b,)."""
    extreme = logs[-1] if side == 0 else logs[0]
    return (1.0 if side == 0 else -1.0), np.flatnonzero(np.abs(logs - extreme) <= BAND * mu)


def log_criterion(criterion: Criterion, alpha: np.ndarray) -> float:
    """Σ_c w_c log σ_extreme at α (n, 2N+1): the criterion, or its log for cond itself."""
    value = criterion.value(alpha)
    return float(np.log(value)) if criterion.objective.exponentiate_extremes else float(value)


def smoothing_bound(criterion: Criterion, alpha: np.ndarray, mu: float = SMOOTHING) -> float:
    """μ Σ_c |w_c| log |B_c| at α (n, 2N+1): how much f_μ exceeds the (log) criterion there at most."""
    logs = np.log(criterion.floored_singular_values(alpha))
    sides = criterion.objective.weighed_extremes
    return float(sum(abs(w) * mu * np.log(_band(logs, side, mu)[1].size) for side, w in sides))
