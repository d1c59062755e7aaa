"""Condition number of the stacked base regressor C = [C₀; Ŷ_B] (Eqs. 5, 41) and its analytic gradient.

With C = U Σ Vᵀ, Eq. 17 gives ∂c/∂C = (1/σ_b) u₁v₁ᵀ − (σ₁/σ_b²) u_b v_bᵀ. The rows of C at instant t are
Y(x_t) X, and Y(x_t) φ = τ(x_t; φ) is inverse dynamics, so (Eqs. 45–47)

    ∂c/∂x_t = Σ_{r∈{1,b}} w_r u_{r,t}ᵀ ∂τ(x_t; φ = X v_r)/∂x_t,   w₁ = 1/σ_b,  w_b = −σ₁/σ_b².

∂τ/∂x_t comes from pinocchio's analytic RNEA derivatives evaluated with the "virtual" inertial
parameters X v_r. These need not be physical; since τ is linear in φ, each is evaluated as
τ(φ_s + X v_r) − τ(φ_s) with φ_s a set of point masses at the joint origins heavy enough that no body
ends up with zero mass. The result is chained with the constant Fourier basis (Eq. 49).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from excite_cli.base_parameters import BaseParameters
from excite_cli.robot import Robot
from excite_cli.trajectory import FourierBasis

#: σ_b is floored at this fraction of σ₁, so rank loss gives a large finite value, never NaN.
RANK_FLOOR = 1e-14


def condition_number(C: np.ndarray) -> float:
    """cond(C) = σ_max / σ_min (Eq. 5) of an (M, b) matrix; ``inf`` if C has fewer rows than columns or is zero."""
    if C.shape[0] < C.shape[1]:
        return float("inf")
    s = np.linalg.svd(C, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


@dataclass
class ConditionNumber:
    """The criterion c(α) = cond([C₀; Ŷ_B(α)]) (or log c) with its gradient in the Fourier coefficients.

    Attributes:
        robot: the robot.
        base: its base parameters (composition matrix X).
        basis: Fourier basis at the T cost samples.
        prior: C₀, (m₁, b) rows stacked above the trajectory's regressor (Eq. 41), or an empty array.
        log: optimize log(cond) instead of cond.
    """

    robot: Robot
    base: BaseParameters
    basis: FourierBasis
    prior: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    log: bool = True
    _models: list[pin.Model] = field(init=False, repr=False)
    _datas: list[pin.Data] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.prior.size == 0:
            self.prior = np.zeros((0, self.base.count))
        if self.prior.shape[1] != self.base.count:
            raise ValueError(f"prior has {self.prior.shape[1]} columns, the robot has {self.base.count} base parameters")
        self._models, self._datas = [], []  # the gradient's model copies, made on first use

    def regressor(self, alpha: np.ndarray) -> np.ndarray:
        """Ŷ_B of the trajectory α (n, 2N+1): (T·n_rows, b) (Eq. 3 with Y_B = Y X)."""
        Q, QD, QDD = self.basis.evaluate(alpha)
        return self.robot.regressor_stack(Q, QD, QDD) @ self.base.composition_matrix

    def stacked(self, own: np.ndarray) -> np.ndarray:
        """C = [C₀; Ŷ_B] (Eq. 41)."""
        return np.vstack([self.prior, own])

    def value(self, alpha: np.ndarray) -> float:
        """c(α), or log c(α) when ``log``."""
        c = condition_number(self.stacked(self.regressor(alpha)))
        return float(np.log(c)) if self.log else c

    def value_and_gradient(self, alpha: np.ndarray) -> tuple[float, np.ndarray]:
        """c(α) (or log c) and its gradient, shaped like α (n, 2N+1) (Eqs. 17, 45–49).

        Ties σ₁ = σ₂ give one valid subgradient (that of the SVD's basis); rank loss is floored
        (``RANK_FLOOR``) so the result is finite.
        """
        Q, QD, QDD = self.basis.evaluate(alpha)
        C = self.stacked(self.robot.regressor_stack(Q, QD, QDD) @ self.base.composition_matrix)
        # σ and v of the extreme singular pairs from the b×b Gram matrix, u = C v / σ: only four
        # singular vectors are needed, not the full SVD (Eqs. 8, 16).
        eig, V = np.linalg.eigh(C.T @ C)
        s_max = np.sqrt(max(eig[-1], 0.0))
        s_min = max(np.sqrt(max(eig[0], 0.0)), RANK_FLOOR * s_max)
        c = s_max / s_min
        w_max, w_min = 1.0 / s_min, -s_max / s_min**2
        if self.log:
            w_max, w_min = w_max / c, w_min / c
        T, rows = Q.shape[0], self.robot.n_rows
        own = slice(self.prior.shape[0], None)
        u_max = (C[own] @ V[:, -1]).reshape(T, rows) * (w_max / s_max)
        u_min = (C[own] @ V[:, 0]).reshape(T, rows) * (w_min / s_min)
        phis = self.base.composition_matrix @ np.stack([V[:, -1], V[:, 0]], axis=1)
        self._set_virtual_parameters(phis)
        # Row weights padded to the model's nv, for the shift pass and the two virtual passes.
        weights = np.zeros((3, T, self.robot.model.nv))
        weights[1][:, self.robot.row_idx] = u_max
        weights[2][:, self.robot.row_idx] = u_min
        weights[0] = -(weights[1] + weights[2])
        grads = np.zeros((3, T, self.robot.model.nv))
        for t in range(T):
            state = self.robot.state(Q[t], QD[t], QDD[t])
            for model, data, w in zip(self._models, self._datas, weights[:, t]):
                dq, dqd, dqdd = pin.computeRNEADerivatives(model, data, *state)
                grads[0, t] += w @ dq
                grads[1, t] += w @ dqd
                grads[2, t] += w @ dqdd
        value = float(np.log(c)) if self.log else float(c)
        return value, self.basis.chain(*grads[:, :, self.robot.v_idx])

    def _set_virtual_parameters(self, phis: np.ndarray) -> None:
        """Models 0, 1, 2 get inertias φ_s, φ_s + φ₁, φ_s + φ₂ from ``phis`` (p, 2)."""
        if not self._models:
            self._models = [pin.Model(self.robot.model) for _ in range(3)]
            self._datas = [m.createData() for m in self._models]
        blocks = phis.reshape(-1, 10, 2)
        masses = 1.0 + 2.0 * np.abs(blocks[:, 0, :]).max(axis=1)
        for j in range(blocks.shape[0]):
            shift = np.zeros(10)
            shift[0] = masses[j]
            self._models[0].inertias[j + 1] = pin.Inertia.FromDynamicParameters(shift)
            for r in range(2):
                self._models[r + 1].inertias[j + 1] = pin.Inertia.FromDynamicParameters(shift + blocks[j, :, r])
