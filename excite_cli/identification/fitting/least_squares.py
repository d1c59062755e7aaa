"""Base parameters and effect coefficients by (weighted) least squares (Eq. 4), and the torques a
fitted model predicts.

Weighted least squares follows Gautier (1997): each joint's rows are weighted by 1/σ_j, σ_j the
residual standard deviation of that joint under ordinary least squares of the rigid-body model,
fixed for every fit of one identification (the effect selection's and the final one), so the
reported model is the one that was scored. Coulomb, viscous and armature coefficients are kept ≥ 0
(:data:`~excite_cli.effects.NONNEGATIVE`, bounded least squares where the plain
solution breaks a bound: :func:`~excite_cli.identification.fitting.normal.solve`); the standard
deviations are those of the unbounded problem. The estimates' standard deviations come from
σ² (AᵀWA)⁻¹ (white residuals), or, given AᵀWΣWA from the residuals' spectra
(:mod:`~excite_cli.identification.fitting.noise`: filtered residuals are correlated), from the
sandwich (AᵀWA)⁻¹ (AᵀWΣWA) (AᵀWA)⁻¹, as the reported fit's are. Every fit goes through the
per-joint normal equations of :mod:`excite_cli.identification.fitting.normal` (no design matrix is formed).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.normal import NormalEquations, covariance_diagonal, solve, sse


@dataclass(frozen=True)
class Fit:
    """A least-squares fit.

    Attributes:
        x: (p,) estimates; std: (p,) their standard deviations.
        sigma: (n,) per-joint residual standard deviation [Nm] of this fit.
        held: (p,) the unknowns held at their bound 0 (friction, armature: ``NONNEGATIVE``), which have
            no two-sided standard deviation; none when empty.
        between: (p,) the standard deviations over the groups of the data fitted, model error
            included (:mod:`~excite_cli.identification.fitting.model_error`; NaN where undefined), or
            None: not computed; spread_by: the groups, ``trajectories`` (3 or more distinct ones) or
            ``time blocks`` (fewer); groups: how many there are.
    """

    x: np.ndarray
    std: np.ndarray
    sigma: np.ndarray
    held: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    between: np.ndarray | None = None
    spread_by: str = ""
    groups: int = 0


def least_squares(
    normal: NormalEquations,
    effects: list[Term],
    weights: np.ndarray | None = None,
    middle: np.ndarray | None = None,
) -> Fit:
    """Ordinary (Eq. 4) or weighted least squares of the model [Y_B, ``effects``] with standard
    deviations (module docstring).

    Args:
        normal: the data's normal equations.
        weights: (n,) weight of each joint's rows (WLS, see :func:`joint_weights`), or None (LS).
        middle: (m, m) AᵀWΣWA for the sandwich (m the model's unknowns), or None for σ² (AᵀWA)⁻¹.
    """
    G, c, s = normal.system(weights, effects)
    bounded = normal.nonnegative(effects)
    x = solve(G, c, bounded)
    dof = max(1, normal.rows - x.size)
    s2 = sse(G, c, s, x) / dof
    sigma = np.sqrt(normal.joint_sse(x, effects) / (normal.rows / normal.n) / (dof / normal.rows))
    variance = s2 * covariance_diagonal(G) if middle is None else covariance_diagonal(G, middle)
    return Fit(x, np.sqrt(np.maximum(variance, 0.0)), sigma, bounded & (x == 0.0))


def joint_weights(normal: NormalEquations, weighted: bool) -> np.ndarray | None:
    """(n,) WLS weights 1/σ_j, σ_j the rigid-body least-squares residual of joint j (Gautier 1997),
    or None for LS. Fixed for the whole selection and the final fit, so the reported model is the
    one the selection scored."""
    if not weighted:
        return None
    return 1.0 / np.maximum(least_squares(normal, []).sigma, 1e-12)


def torque_errors(measured: np.ndarray, predicted: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per joint, of measured and predicted torques (N, n) [Nm]: the RMS error (n,) [Nm], the RMS of
    the measured torque (n,) [Nm] and their ratio (n,) [%] (relative to 1 Nm where a joint's torque
    is zero)."""
    rms = np.sqrt(np.mean((measured - predicted) ** 2, axis=0))
    torque = np.sqrt(np.mean(measured**2, axis=0))
    return rms, torque, 100.0 * rms / np.where(torque > 0, torque, 1.0)


def predict(data: Dataset, x: np.ndarray, effects: list[Term]) -> np.ndarray:
    """Predicted torques (N, n) [Nm] of the model [Y_B, effects] with coefficients x (base
    parameters first), without forming the design."""
    b = data.regressor.shape[1]
    out = (data.regressor @ x[:b]).reshape(-1, data.n)
    k = b
    for t in effects:
        cols = data.blocks[t]
        out += np.outer(cols @ x[k : k + cols.shape[1]], t.rows(data.n))
        k += cols.shape[1]
    return out
