"""Least squares of the identification model through normal equations kept per joint.

Every row of the design [Y_B, effect blocks] belongs to one joint, and an effect block of joint j is
zero outside joint j's rows. So the weighted normal equations of any model (a subset of effect
blocks) and any per-joint weights w_j are sums over joints of per-joint pieces

    G = Σ_j w_j² L_jᵀL_j,  c = Σ_j w_j² L_jᵀτ_j,  s = Σ_j w_j² τ_jᵀτ_j,

L_j = [Y_B rows of joint j, every candidate block of joint j], computed once. A fit then costs a
solve of the size of the model, its residual sum of squares is s − 2xᵀc + xᵀGx, and the full
design is never formed: memory follows the decimated data, not the number of candidates × steps.
Columns are scaled to unit diagonal before solving (normal equations square the condition number;
the regressors here stay below ~1e4).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from excite_cli.identification.dataset import Dataset

#: A candidate block keeps less than this fraction of its squared norm outside the model's span:
#: not separately identifiable (above the ~1e-10 rounding floor of squared normal equations).
ABSORBED = 1e-8


class NormalEquations:
    """Per-joint normal equations of a dataset's base regressor and the candidate blocks ``keys``.

    Args:
        data: the samples (base regressor, torques, effect blocks).
        keys: the (effect, joint) blocks that models may contain.
    """

    def __init__(self, data: Dataset, keys: list[tuple[str, int]]):
        n, b = data.n, data.regressor.shape[1]
        self.n, self.b, self.rows = n, b, data.tau.size
        self.local: list[dict[tuple[str, int], np.ndarray]] = []
        self.G, self.c, self.s = [], [], []
        for j in range(n):
            own = [key for key in keys if key[1] == j]
            sizes = [data.blocks[key].shape[1] for key in own]
            starts = b + np.concatenate([[0], np.cumsum(sizes)]).astype(int)
            self.local.append({key: np.arange(starts[k], starts[k + 1]) for k, key in enumerate(own)})
            L = np.hstack([data.regressor[j::n]] + [data.blocks[key] for key in own])
            tau = data.tau[j::n]
            self.G.append(L.T @ L)
            self.c.append(L.T @ tau)
            self.s.append(float(tau @ tau))

    def columns(self, effects: list[tuple[str, int]]) -> int:
        """Number of unknowns of the model [Y_B, ``effects``]."""
        return self.b + sum(self.local[j][(e, j)].size for e, j in effects)

    def system(self, weights: np.ndarray | None, effects: list[tuple[str, int]]) -> tuple[np.ndarray, np.ndarray, float]:
        """(G, c, s) of the model [Y_B, ``effects``] (unknowns in that order) with joint weights (n,)."""
        m = self.columns(effects)
        G, c, s = np.zeros((m, m)), np.zeros(m), 0.0
        place, start = [], self.b
        for e, j in effects:
            size = self.local[j][(e, j)].size
            place.append((j, self.local[j][(e, j)], np.arange(start, start + size)))
            start += size
        for j in range(self.n):
            w2 = 1.0 if weights is None else float(weights[j]) ** 2
            mine = [(loc, glob) for jj, loc, glob in place if jj == j]
            local = np.concatenate([np.arange(self.b)] + [loc for loc, _ in mine])
            glob = np.concatenate([np.arange(self.b)] + [g for _, g in mine])
            G[np.ix_(glob, glob)] += w2 * self.G[j][np.ix_(local, local)]
            c[glob] += w2 * self.c[j][local]
            s += w2 * self.s[j]
        return G, c, s

    def joint_sse(self, x: np.ndarray, effects: list[tuple[str, int]]) -> np.ndarray:
        """(n,) unweighted residual sum of squares of each joint [Nm²] for coefficients x."""
        out = np.zeros(self.n)
        start, blocks = self.b, []
        for e, j in effects:
            size = self.local[j][(e, j)].size
            blocks.append((j, self.local[j][(e, j)], np.arange(start, start + size)))
            start += size
        for j in range(self.n):
            local = np.concatenate([np.arange(self.b)] + [loc for jj, loc, _ in blocks if jj == j])
            xj = x[np.concatenate([np.arange(self.b)] + [g for jj, _, g in blocks if jj == j])]
            G = self.G[j][np.ix_(local, local)]
            out[j] = max(self.s[j] - 2.0 * xj @ self.c[j][local] + xj @ G @ xj, 0.0)
        return out


def solve(G: np.ndarray, c: np.ndarray) -> np.ndarray:
    """x of G x = c, columns scaled to unit diagonal (minimum-norm where G is singular)."""
    d = np.sqrt(np.diag(G))
    d[d == 0] = 1.0
    scaled = G / np.outer(d, d)
    try:
        z = scipy.linalg.cho_solve(scipy.linalg.cho_factor(scaled), c / d)
    except np.linalg.LinAlgError:
        z = np.linalg.lstsq(scaled, c / d, rcond=1e-13)[0]
    return z / d


def sse(G: np.ndarray, c: np.ndarray, s: float, x: np.ndarray) -> float:
    """Residual sum of squares s − 2xᵀc + xᵀGx (≥ 0)."""
    return max(s - 2.0 * x @ c + x @ G @ x, 0.0)


def outside_fraction(G: np.ndarray, model: int) -> float:
    """Fraction of the squared norm of the last columns (after the first ``model``) outside the span
    of the first ones: the Schur complement's trace over the block's, with unit-diagonal scaling."""
    d = np.sqrt(np.diag(G))
    d[d == 0] = 1.0
    scaled = G / np.outer(d, d)
    S, C, SC = scaled[:model, :model], scaled[model:, model:], scaled[:model, model:]
    inside = SC.T @ np.linalg.lstsq(S, SC, rcond=1e-13)[0]
    return float(np.trace(C - inside) / max(np.trace(C), 1e-300))


def covariance_diagonal(G: np.ndarray) -> np.ndarray:
    """diag(G⁻¹) with unit-diagonal scaling."""
    d = np.sqrt(np.diag(G))
    d[d == 0] = 1.0
    inverse = np.linalg.pinv(G / np.outer(d, d), rcond=1e-13, hermitian=True)
    return np.diag(inverse) / d**2
