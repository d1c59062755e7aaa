"""Condition number of the stacked base regressor C = [C₀; Ŷ_B] (Eqs. 5, 41) and its analytic gradient.

With C = U Σ Vᵀ, Eq. 17 gives ∂c/∂C = (1/σ_b) u₁v₁ᵀ − (σ₁/σ_b²) u_b v_bᵀ. The rows of C at instant t are
Y(x_t) X, and Y(x_t) φ = τ(x_t; φ) is inverse dynamics, so (Eqs. 45–47)

    ∂c/∂x_t = Σ_{r∈{1,b}} w_r u_{r,t}ᵀ ∂τ(x_t; φ = X v_r)/∂x_t,   w₁ = 1/σ_b,  w_b = −σ₁/σ_b².

∂τ/∂x_t comes from pinocchio's analytic RNEA derivatives evaluated with the "virtual" inertial
parameters X v_r. These need not be physical, but pinocchio needs a non-zero mass on every body;
since τ is linear in φ, each is evaluated with φ_s + X v_r, where the shift φ_s gives every body a
point mass and makes no torque for any motion (point masses on revolute axes, cancelled on the
parent body), so two RNEA-derivative passes per instant suffice. The result is chained with the
constant Fourier basis (Eq. 49).
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
    _unit_shift: np.ndarray = field(init=False, repr=False)
    _prior_gram: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.prior.size == 0:
            self.prior = np.zeros((0, self.base.count))
        if self.prior.shape[1] != self.base.count:
            raise ValueError(f"prior has {self.prior.shape[1]} columns, the robot has {self.base.count} base parameters")
        self._models, self._datas = [], []  # the gradient's model copies, made on first use
        self._prior_gram = self.prior.T @ self.prior

    def regressor(self, alpha: np.ndarray) -> np.ndarray:
        """Ŷ_B of the trajectory α (n, 2N+1): (T·n_rows, b) (Eq. 3 with Y_B = Y X)."""
        Q, QD, QDD = self.basis.evaluate(alpha)
        return self.robot.regressor_stack(Q, QD, QDD)[:, self.base.independent]  # Y X, X a selection

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
        own = self.regressor(alpha)
        # σ and v of the extreme singular pairs from the b×b Gram matrix CᵀC = C₀ᵀC₀ + ŶᵀŶ, u = C v / σ:
        # only four singular vectors are needed, not the full SVD (Eqs. 8, 16).
        eig, V = np.linalg.eigh(self._prior_gram + own.T @ own)
        s_max = np.sqrt(max(eig[-1], 0.0))
        s_min = max(np.sqrt(max(eig[0], 0.0)), RANK_FLOOR * s_max)
        c = s_max / s_min
        w_max, w_min = 1.0 / s_min, -s_max / s_min**2
        if self.log:
            w_max, w_min = w_max / c, w_min / c
        T, rows = Q.shape[0], self.robot.n_rows
        u_max = (own @ V[:, -1]).reshape(T, rows) * (w_max / s_max)
        u_min = (own @ V[:, 0]).reshape(T, rows) * (w_min / s_min)
        phis = np.zeros((self.robot.n_parameters, 2))
        phis[self.base.independent] = V[:, [-1, 0]]  # X v_r
        models, datas = self._virtual_models(phis)
        # Row weights padded to the model's nv, for the two virtual passes (and the shift pass).
        weights = np.zeros((len(models), T, self.robot.model.nv))
        weights[0][:, self.robot.row_idx] = u_max
        weights[1][:, self.robot.row_idx] = u_min
        if len(models) == 3:
            weights[2] = -(weights[0] + weights[1])
        derivatives = np.empty((len(models), 3, T, self.robot.model.nv, self.robot.model.nv))
        states = self._states(Q, QD, QDD)
        for t in range(T):
            for m, (model, data) in enumerate(zip(models, datas)):
                derivatives[m, :, t] = pin.computeRNEADerivatives(model, data, states[0][t], states[1][t], states[2][t])
        grads = np.einsum("mtv,mktvw->ktw", weights, derivatives)  # Σ_r w_rᵀ ∂τ(φ_r)/∂(q, q̇, q̈)
        value = float(np.log(c)) if self.log else float(c)
        return value, self.basis.chain(*grads[:, :, self.robot.v_idx])

    def _states(self, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Full-model (q, v, a) at every instant, (T, nq), (T, nv), (T, nv), from the active joints' (T, n)."""
        robot = self.robot
        qf = np.tile(robot.q_reference, (Q.shape[0], 1))
        vf, af = np.zeros((Q.shape[0], robot.model.nv)), np.zeros((Q.shape[0], robot.model.nv))
        qf[:, robot.q_idx], vf[:, robot.v_idx], af[:, robot.v_idx] = Q, QD, QDD
        return qf, vf, af

    def _virtual_models(self, phis: np.ndarray) -> tuple[list[pin.Model], list[pin.Data]]:
        """Models with inertias φ_s + φ₁ and φ_s + φ₂ from ``phis`` (p, 2), and a third with φ_s alone
        when φ_s makes torques (a prismatic joint moves).

        φ_s puts on each body a point mass M_j at its joint's origin, M_j = m_s × (bodies in the
        joint's subtree), m_s = 1 + 2 |largest mass in φ_r|; for a revolute joint, −M_j at the same
        point of the parent body cancels it, so each body keeps a net mass m_s. That point does not
        move relative to the parent and lies on the joint's axis, so φ_s makes no torque at any joint
        for any motion (it is in the regressor's null space) and needs no pass of its own.
        """
        model = self.robot.model
        if not self._models:
            self._models = [pin.Model(model) for _ in range(2 if self._shift_free() else 3)]
            self._datas = [m.createData() for m in self._models]
            self._unit_shift = self._shift_per_mass() @ self._subtree_sizes()
        blocks = phis.reshape(-1, 10, 2)
        shift = (1.0 + 2.0 * np.abs(blocks[:, 0, :]).max()) * self._unit_shift
        for j in range(1, model.njoints):
            own = shift[10 * (j - 1):10 * j]
            for r in range(2):
                self._models[r].inertias[j] = pin.Inertia.FromDynamicParameters(own + blocks[j - 1, :, r])
            if len(self._models) == 3:
                self._models[2].inertias[j] = pin.Inertia.FromDynamicParameters(own)
        return self._models, self._datas

    def _shift_free(self) -> bool:
        """Whether every moving joint is revolute (then φ_s makes no torque)."""
        model = self.robot.model
        return all(model.joints[j].shortname().startswith("JointModelR")
                   for j in range(1, model.njoints) if model.joints[j].idx_v in self.robot.v_idx)

    def _subtree_sizes(self) -> np.ndarray:
        """(njoints − 1,) bodies in the subtree of each joint, itself included."""
        parents = self.robot.model.parents
        sizes = np.ones(len(parents))
        for j in range(len(parents) - 1, 0, -1):
            sizes[parents[j]] += sizes[j]
        return sizes[1:]

    def _shift_per_mass(self) -> np.ndarray:
        """(p, njoints − 1): the dynamic parameters of φ_s per unit of each M_j (see :meth:`_virtual_models`)."""
        model = self.robot.model
        A = np.zeros((10 * (model.njoints - 1), model.njoints - 1))
        for j in range(1, model.njoints):
            A[10 * (j - 1), j - 1] = 1.0
            parent = model.parents[j]
            if parent > 0 and model.joints[j].shortname().startswith("JointModelR"):
                point = pin.Inertia(1.0, model.jointPlacements[j].translation, np.zeros((3, 3)))
                A[10 * (parent - 1):10 * parent, j - 1] = -point.toDynamicParameters()
        return A
