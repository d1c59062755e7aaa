"""Condition number (or D-, E-optimality) of the stacked base regressor C = [C₀; Ŷ_B] (Eqs. 5, 41)
and its analytic gradient.

With C = U Σ Vᵀ, Eq. 17 gives ∂c/∂C = (1/σ_b) u₁v₁ᵀ − (σ₁/σ_b²) u_b v_bᵀ. The rows of C at instant t are
Y(x_t) X, and Y(x_t) φ = τ(x_t; φ) is inverse dynamics, so (Eqs. 45–47)

    ∂c/∂x_t = Σ_{r∈{1,b}} w_r u_{r,t}ᵀ ∂τ(x_t; φ = X v_r)/∂x_t,   w₁ = 1/σ_b,  w_b = −σ₁/σ_b².

Every criterion's gradient in C is Σ_r a_r (C v_r) v_rᵀ = C A, so the sum is Σ_k ∂τ_k(x_t; φ_{t,k})/∂x_t with
"virtual" inertial parameters φ_{t,k} = X A C_tᵀ e_k per instant and row, one reverse pass of RNEA per
instant (:mod:`excite_cli.dynamics.regressor_adjoint`). The result is chained with the constant Fourier
basis (Eq. 49).

D-, E- and A-optimality have gradients of the same form, Σ_r a_r (C v_r) v_rᵀ over eigenvectors v_r
of CᵀC (:meth:`~excite_cli.criteria.record.CriterionRecord.terms`): −log σ_min needs one, −log det(CᵀC)/b
all b; the reverse pass costs the same for any number.

With a frame L (b, b) every criterion is that of C L instead of C (``optimizer.scaling: urdf``, the
regressor in a basis of the identifiable subspace that does not depend on the choice of base columns,
:func:`~excite_cli.design.information.scaled_frame`); with eigenvectors ṽ_r of LᵀCᵀCL the
gradient in C is Σ_r a_r (C L ṽ_r)(L ṽ_r)ᵀ, so A = Σ_r a_r L ṽ_r (L ṽ_r)ᵀ.

With effect columns (``effects``: friction, armature, offsets, coupled motors) C = [Y_B | Y_E] per row
and v_r = (v_{r,B}, v_{r,E}): the base part goes through the reverse pass as above, the effect part
through the effect columns' own derivatives in q̇ and q̈
(:meth:`~excite_cli.dynamics.effect_columns.EffectColumns.chain`; Coulomb friction through the smooth
sign tanh(q̇/v_c) with the config's ``effects.coulomb_velocity``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from excite_cli.criteria import CriterionRecord
from excite_cli.criteria.record import RANK_FLOOR
from excite_cli.design.information import PriorInformation
from excite_cli.design.noise import RowNoise
from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.effect_columns import EffectColumns
from excite_cli.dynamics.regressor_adjoint import RegressorAdjoint
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.memo import once
from excite_cli.trajectory.fourier import FourierBasis

#: The smallest eigenvalue of CᵀC, relative to the largest, down to which the eigenvalues of CᵀC give
#: the criterion (cond(C) ≤ 10⁴; their relative error is about 1e-16 λ_max/λ_min, so ≤ 1e-8 there, below a
#: line search's steps: the default's cond(CL) is 1600–1800 on the G1); below it the singular values of C do.
GRAM_ACCURATE = 1e-8


def condition_number(C: np.ndarray) -> float:
    """cond(C) = σ_max / σ_min (Eq. 5) of an (M, b) matrix; ``inf`` if C has fewer rows than columns or is zero."""
    if C.shape[0] < C.shape[1]:
        return float("inf")
    s = np.linalg.svd(C, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


@dataclass
class Criterion:
    """The criterion f(α) of the stacked base regressor C = [C₀; Ŷ_B(α)] (``objective``, one record of
    :data:`~excite_cli.criteria.CRITERIA`) with its gradient in the Fourier coefficients.

    Attributes:
        robot: the robot.
        base: its base parameters (composition matrix X).
        basis: Fourier basis at the T cost samples.
        objective: the criterion's record (:data:`~excite_cli.criteria.CRITERIA`).
        prior: what the criterion needs of C₀, the (m₁, b+e) rows stacked above the trajectory's
            regressor (Eq. 41): their Gram matrix and triangular factor, or None: no prior rows.
        frame: L (b+e, b+e): the criterion is that of C L (module docstring); None: of C, the paper's.
        effects: e effect columns beside the b base columns, C = [Y_B | Y_E] per row
            (:mod:`~excite_cli.dynamics.effect_columns`), or None: the rigid body alone.
        noise: the rows' noise (:mod:`~excite_cli.design.noise`): each row of the trajectory
            weighs σ̄/√(σ_j² + ρ_j² τ_j(t)²), or None: unweighted.
    """

    robot: Robot
    base: BaseParameters
    basis: FourierBasis
    objective: CriterionRecord
    prior: PriorInformation | None = None
    frame: np.ndarray | None = None
    effects: EffectColumns | None = None
    noise: RowNoise | None = None
    _dynamics: RegressorAdjoint = field(init=False, repr=False)
    _data: pin.Data = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.prior is None:
            self.prior = PriorInformation.of(np.zeros((0, self.columns)))
        if self.prior.gram.shape[1] != self.columns:
            raise ExciteError(
                "sequence.prior",
                f"{self.prior.gram.shape[1]} columns, but the design has {self.base.count} base parameters"
                + (f" and {self.effects.count} effect columns" if self.effects else ""),
            )
        self._dynamics = RegressorAdjoint(self.robot)
        self._data = self.robot.model.createData()  # this criterion's own, so no result depends on other users

    @property
    def columns(self) -> int:
        """b + e: the base parameters and the effect columns."""
        return self.base.count + (self.effects.count if self.effects else 0)

    def framed(self, C: np.ndarray) -> np.ndarray:
        """C L (M, b) with the criterion's frame L, or C without one."""
        return C if self.frame is None else C @ self.frame

    def regressor(self, alpha: np.ndarray) -> np.ndarray:
        """Ŷ_B of the trajectory α (n, 2N+1): (T·n_rows, b) (Eq. 3 with Y_B = Y X), and its effect
        columns beside it when there are any: (T·n_rows, b+e); each row weighed by its noise when the
        criterion has one."""
        return self._regressor(*self.basis.evaluate(alpha))[0]

    def _regressor(self, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> tuple:
        """The weighed rows Ŷ (T·n_rows, b+e), their weights s and ds/dτ (T·n_rows,) (None without noise)."""
        full = self.robot.regressor_stack(Q, QD, QDD, self._data)
        own = full[:, self.base.independent]  # Y X, X a selection
        own = own if self.effects is None else np.hstack([own, self.effects.columns(QD, QDD)])
        if self.noise is None:
            return own, None, None
        s, ds = self.noise.weights(full @ self.noise.reference)  # τ = Y φ_URDF
        return own * s[:, None], s, ds

    def stacked(self, own: np.ndarray) -> np.ndarray:
        """[R; Ŷ_B], R the triangular factor of C₀: the singular values of C = [C₀; Ŷ_B] (Eq. 41)."""
        return np.vstack([self.prior.factor, own])

    def value(self, alpha: np.ndarray, from_gram: bool = False) -> float:
        """f(α), from the singular values of C (accurate also where CᵀC is not).

        Args:
            from_gram: from the eigenvalues of the b×b matrix CᵀC instead, as :meth:`value_and_gradient`
                takes them, where they are accurate to about 1e-8 relative (cond(C) ≤ 10⁴,
                :data:`GRAM_ACCURATE`; else still from the singular values): a solver's line search, in
                about half the time (G1, 560 × 90: 0.9 ms against 1.7 ms with the regressor, one BLAS
                thread); finite differences need the singular values.
        """
        Q, QD, QDD, own, _, _ = self._motion(alpha)
        if Q.shape[0] * self.robot.n_rows + self.prior.rows < self.columns:
            return float("inf")
        eig = np.linalg.eigvalsh(self._gram(alpha)) if from_gram else None
        if eig is None or eig[0] < GRAM_ACCURATE * eig[-1]:
            eig = np.linalg.svd(self.framed(self.stacked(own)), compute_uv=False)[::-1] ** 2
        return self.objective.terms(eig)[0]

    def _motion(self, alpha: np.ndarray) -> tuple:
        """Q, Q̇, Q̈ (T, n) of α, its regressor rows Ŷ (T·n_rows, b+e) and their weights s and ds/dτ
        (:meth:`_regressor`), kept for the next call at the same α (a solver asks for the value, then
        the gradient, at each accepted point)."""

        def compute() -> tuple:
            Q, QD, QDD = self.basis.evaluate(alpha)
            return (Q, QD, QDD, *self._regressor(Q, QD, QDD))

        return once(self, "motion", alpha, compute)

    def _gram(self, alpha: np.ndarray) -> np.ndarray:
        """CᵀC = C₀ᵀC₀ + ŶᵀŶ (b×b, Eq. 41) at α, or Lᵀ CᵀC L with the frame; kept for the next call at
        the same α (a solver's trial point's value, then its gradient)."""

        def compute() -> np.ndarray:
            own = self._motion(alpha)[3]
            gram = self.prior.gram + own.T @ own
            return gram if self.frame is None else self.frame.T @ gram @ self.frame

        return once(self, "gram", alpha, compute)

    def value_and_gradient(self, alpha: np.ndarray) -> tuple[float, np.ndarray]:
        """f(α) and its gradient, shaped like α (n, 2N+1) (Eqs. 17, 45–49).

        Ties σ₁ = σ₂ give one valid subgradient (that of the eigenbasis); rank loss is floored
        (:data:`~excite_cli.criteria.record.RANK_FLOOR`) so the result is finite.
        """
        motion = self._motion(alpha)
        # eigenpairs of the b×b Gram matrix CᵀC = C₀ᵀC₀ + ŶᵀŶ give σ² and v; C v = σ u (Eqs. 8, 16)
        eig, V = np.linalg.eigh(self._gram(alpha))
        value, used, coefficients = self.objective.terms(eig)
        return value, self._chained(motion, V[:, used], coefficients)

    def singular_values(self, alpha: np.ndarray) -> np.ndarray:
        """σ (b,) of C (of C L with the frame), ascending, from the eigenvalues of CᵀC."""
        return np.sqrt(np.maximum(np.linalg.eigvalsh(self._gram(alpha)), 0.0))

    def floored_singular_values(self, alpha: np.ndarray) -> np.ndarray:
        """σ (b,) as :meth:`singular_values`, floored as the criterion floors them
        (:data:`~excite_cli.criteria.record.RANK_FLOOR` σ_max): rank loss gives finite logs."""
        sigma = self.singular_values(alpha)
        return np.maximum(sigma, max(RANK_FLOOR * sigma[-1], np.finfo(float).tiny))

    def log_singular_values(self, alpha: np.ndarray, indices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """log σ_i (k,) of C (of C L with the frame) for the singular values ``indices`` (k,) (ascending
        order), and their gradients in α (k, n, 2N+1): ∂ log σ_i = v_iᵀ Cᵀ∂C v_i / λ_i (Eq. 17's terms one
        at a time; a multiple σ_i has the gradient of the eigenbasis numpy returns). λ is floored as the
        criterion floors it (:data:`~excite_cli.criteria.record.RANK_FLOOR`): rank loss gives finite values."""
        motion = self._motion(alpha)
        eig, V = np.linalg.eigh(self._gram(alpha))
        lam = np.maximum(eig[indices], max((RANK_FLOOR**2) * eig[-1], np.finfo(float).tiny))
        gradients = np.array([self._chained(motion, V[:, [i]], np.array([1.0 / x])) for i, x in zip(indices, lam)])
        return 0.5 * np.log(lam), gradients.reshape(len(indices), *alpha.shape)

    def cluster_gradients(self, alpha: np.ndarray, indices: np.ndarray) -> np.ndarray:
        """The gradients in α (k, k, n, 2N+1) of h_ab = v_aᵀ (CᵀC) v_b / (2 λ̄) for the eigenvectors
        v_a, v_b of CᵀC (of Lᵀ CᵀC L with the frame) of the singular values ``indices`` (k,) of one
        cluster (ascending order), held fixed, λ̄ the mean of their eigenvalues. At a multiple singular
        value σ every subgradient of log σ is Σ_ab S_ab ∇h_ab with S ⪰ 0 of trace 1 (the derivative of
        an eigenvalue of multiplicity k, Overton 1992); h_aa's alone are the gradients of each log σ_a.
        Each off-diagonal pair is two passes: v_aᵀGv_b = ½(u₊ᵀGu₊ − u₋ᵀGu₋), u± = (v_a ± v_b)/√2."""
        motion = self._motion(alpha)
        eig, V = np.linalg.eigh(self._gram(alpha))
        mean = float(max(eig[indices].mean(), np.finfo(float).tiny))
        k = len(indices)
        out = np.zeros((k, k, *alpha.shape))
        for a in range(k):
            for b in range(a, k):
                va, vb = V[:, indices[a]], V[:, indices[b]]
                if a == b:
                    out[a, a] = self._chained(motion, va[:, None], np.array([1.0 / mean]))
                    continue
                plus, minus = np.column_stack([va + vb, va - vb]).T / np.sqrt(2.0)
                both = self._chained(motion, np.column_stack([plus, minus]), np.array([0.5, -0.5]) / mean)
                out[a, b] = out[b, a] = both
        return out

    def _chained(self, motion: tuple, V: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
        """The gradient in α (n, 2N+1) of a criterion whose gradient in C is Σ_r a_r (C v_r) v_rᵀ, from
        the motion (:meth:`_motion`), eigenvectors V (b, R) of the (framed) CᵀC and a_r (R,)."""
        Q, QD, QDD, own, s, ds = motion
        directions = V if self.frame is None else self.frame @ V  # v_r, or L ṽ_r
        T, rows, b = Q.shape[0], self.robot.n_rows, self.base.count
        G = own @ ((directions * coefficients) @ directions.T)  # ∂f/∂C = Σ_r a_r (C v_r) v_rᵀ (M, b+e)
        phis = np.zeros((T * rows, self.robot.n_parameters))  # φ_{t,k} = X (∂f/∂C)_{t,k} (Eq. 47)
        if s is not None:  # C = diag(s) Y: ∂f/∂Y = s ∂f/∂C, and ∂f/∂s = Σ_r a_r (C v_r)(Y v_r)
            if self.noise.varying:  # through the weights: ∂f/∂τ ∂τ(x_t; φ_URDF)/∂x_t
                phis += ((G * own).sum(axis=1) / s * ds)[:, None] * self.noise.reference
            G = G * s[:, None]
        phis[:, self.base.independent] += G[:, :b]
        dq, dqd, dqdd = self._dynamics.row_derivatives(phis.reshape(T, rows, -1), Q, QD, QDD)
        if self.effects is not None:  # ∂f/∂Y_E, through the effect columns' motion
            effect_qd, effect_qdd = self.effects.chain(G[:, b:], QD, QDD)
            dqd, dqdd = dqd + effect_qd, dqdd + effect_qdd
        return self.basis.chain(dq, dqd, dqdd)
