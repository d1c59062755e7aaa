"""Excitation that does not depend on the choice of base columns.

cond(C) depends on which standard-parameter columns form the base (Eq. 2) and on their units, so
two trajectories can rank differently under two choices of base. The standard regressor Y does not
depend on that choice: Y = Y_B K with K (b, p) the regrouping (φ_B = K φ). With Y's columns scaled
by the URDF's parameter magnitudes D = diag(d) (p, p), the b nonzero singular values of Y D have the
product det(C_BᵀC_B)^½ · det(K D² Kᵀ)^½, and another base Y_B T, K' = T⁻¹ K gives the same product.
Their geometric mean

    ē(C) = (det(CᵀC) · det(K D² Kᵀ))^(1 / 2b)   [N·m]

is the torque a trajectory's samples carry per relative change of a parameter, on average over
the b directions the data can identify: a larger ē is more excitation, whichever base columns the
optimizer worked with. log ē is the D-optimal criterion (``optimizer.objective: log_det``, the
paper's ref. [20]) up to a constant.

The same singular values are those of C L, L (b, b) the Cholesky factor of K D² Kᵀ: with
N = (K D)ᵀ L⁻ᵀ (p, b) an orthonormal basis of the identifiable subspace of the scaled parameters
D⁻¹φ, Y D N = C K D Dᵀ Kᵀ L⁻ᵀ = C L. Another base (C T, T⁻¹K) has the factor T⁻¹L Q with Q
orthogonal, so C L Q: the same singular values. cond(C L) is therefore a condition number that does
not depend on which columns form the base (``optimizer.scaling: urdf``): the ratio of the best to
the worst determined direction of the standard parameters, each measured in its URDF magnitude.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.robot import Robot


def parameter_magnitudes(robot: Robot) -> np.ndarray:
    """(p,) the URDF's magnitude d of each standard parameter, per body of mass m: m [kg] for the
    mass, m·ℓ [kg·m] for the first moments, m·ℓ² [kg·m²] for the inertia entries, with ℓ [m] the
    body's radius of gyration about its frame origin, √(tr I_o / 2m). Bodies without mass get 1."""
    blocks = robot.urdf_parameters().reshape(-1, 10)
    d = np.ones_like(blocks)
    for block, row in zip(blocks, d):
        m = block[0]
        if m > 0:
            trace = block[4] + block[6] + block[9]
            length = np.sqrt(max(trace, 0.0) / (2.0 * m))
            row[0], row[1:4], row[4:] = m, m * length, m * length**2
    return np.where(d > 0, d, 1.0).ravel()


def excitation_level(
    C: np.ndarray, base: BaseParameters, magnitudes: np.ndarray, effect_magnitudes: np.ndarray | None = None
) -> float:
    """ē(C) [N·m] (module docstring) of a stacked base regressor C (M, b); 0 when C is rank-deficient.
    With e effect columns beside the base columns (M, b+e), each scaled by its typical magnitude m_k,
    the geometric mean runs over all b+e singular values of C diag(L, m).

    Args:
        C: base-regressor rows (M, b), or (M, b+e) with effect columns [SI].
        base: the base parameters C's columns belong to (regrouping K).
        magnitudes: (p,) parameter magnitudes d (:func:`parameter_magnitudes`).
        effect_magnitudes: (e,) the effect columns' magnitudes, or None.
    """
    sign, logdet = np.linalg.slogdet(C.T @ C) if C.shape[0] >= C.shape[1] else (0.0, -np.inf)
    if sign <= 0:
        return 0.0
    K = base.regrouping * magnitudes
    scale = np.linalg.slogdet(K @ K.T)[1]
    if effect_magnitudes is not None and effect_magnitudes.size:
        scale += 2.0 * np.log(effect_magnitudes).sum()
    return float(np.exp((logdet + scale) / (2 * C.shape[1])))


def scaled_frame(base: BaseParameters, magnitudes: np.ndarray) -> np.ndarray:
    """L (b, b), lower triangular with L Lᵀ = K D² Kᵀ (module docstring): C L is the regressor in an
    orthonormal basis of the identifiable subspace of the URDF-scaled standard parameters.

    Args:
        base: the base parameters (regrouping K, (b, p)).
        magnitudes: (p,) parameter magnitudes d (:func:`parameter_magnitudes`).
    """
    K = base.regrouping * magnitudes
    return np.linalg.cholesky(K @ K.T)


def predicted_std(C: np.ndarray, noise: float) -> np.ndarray:
    """(k,) the standard deviations least squares would give each column's coefficient from rows
    C (M, k) with white noise ``noise`` per row: √diag((CᵀC)⁻¹) · noise (Gautier 1997); inf for a
    coefficient the rows do not determine (its column in the span of the others, or zero)."""
    lam, V = np.linalg.eigh(C.T @ C) if C.shape[0] else (np.zeros(C.shape[1]), np.eye(C.shape[1]))
    seen = lam > 1e-12 * max(lam.max(initial=0.0), np.finfo(float).tiny)
    variance = (V[:, seen] ** 2 / lam[seen]).sum(axis=1)
    unseen = (V[:, ~seen] ** 2).sum(axis=1) > 1e-6
    return np.where(unseen, np.inf, noise * np.sqrt(variance))


@dataclass(frozen=True)
class PriorInformation:
    """What a criterion needs of prior rows C₀ (m, b+e) stacked above a trajectory's (Eq. 41), in
    (b+e)-square blocks however many rows C₀ has: what a restart is sent instead of the rows.

    Attributes:
        gram: C₀ᵀC₀ (b+e, b+e), computed from the rows (the criterion's CᵀC = C₀ᵀC₀ + ŶᵀŶ).
        factor: R (min(m, b+e), b+e) of C₀ = Q R (Householder QR, LAPACK ``geqrf``): [R; Ŷ] has the
            singular values of [C₀; Ŷ] (RᵀR = C₀ᵀC₀), which the criterion takes where CᵀC is not accurate.
        rows: m, the rows C₀ counts (C has fewer rows than columns below b+e − m trajectory rows).
    """

    gram: np.ndarray
    factor: np.ndarray
    rows: int

    @classmethod
    def of(cls, rows: np.ndarray) -> "PriorInformation":
        """The information of C₀ = ``rows`` (m, b+e); m may be 0."""
        factor = np.linalg.qr(rows, mode="r") if rows.shape[0] else rows
        return cls(rows.T @ rows, factor, rows.shape[0])
