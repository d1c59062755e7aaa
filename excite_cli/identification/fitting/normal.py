"""Least squares of the identification model through normal equations kept per joint.

Every row of the design [Y_B, effect blocks] belongs to one joint, and an effect block of joint j is
zero outside joint j's rows (a coupled term's block is nonzero on each of its joints' rows, times the
joint's weight in its coupling: it is placed in each of those joints' pieces, with the same
unknowns). So the weighted normal equations of any model (a subset of effect blocks) and any
per-joint weights w_j are sums over joints of per-joint pieces

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
import scipy.optimize

from excite_cli.identification.effects import Term, nonnegative_columns
from excite_cli.identification.fitting.dataset import Dataset

#: A candidate block keeps less than this fraction of its squared norm outside the model's span:
#: not separately identifiable (above the ~1e-10 rounding floor of squared normal equations).
ABSORBED = 1e-8
#: An eigenvalue or Cholesky pivot of unit-diagonal normal equations below this fraction of the
#: largest is rounding: every pseudo-inverse here cuts there (healthy fits' pivots sit above 1e-11).
ROUNDING = 1e-13
#: Instants stacked at a time when the normal equations are summed.
CHUNK = 20_000


class NormalEquations:
    """Per-joint normal equations of a dataset's base regressor and the candidate blocks ``keys``.

    Args:
        data: the samples (base regressor, torques, effect blocks).
        keys: the terms (effect blocks) that models may contain.
        rows: (m,) the instants to use (default all), e.g. one fold of a cross-validation.
        scale: (N, n) a factor for each instant's row of each joint, regressor and torque alike (the
            weights of a feasible generalized least squares, :func:`weighted_fit`), or None: 1.
    """

    def __init__(
        self, data: Dataset, keys: list[Term], rows: np.ndarray | None = None, scale: np.ndarray | None = None
    ):
        n, b = data.n, data.regressor.shape[1]
        rows = np.arange(data.time.size) if rows is None else np.asarray(rows)
        self.n, self.b, self.rows = n, b, rows.size * n
        self.local: list[dict[Term, np.ndarray]] = []
        self.G, self.c, self.s = [], [], []
        self.size = {key: data.blocks[key].shape[1] for key in keys}
        for j in range(n):
            own = [key for key in keys if j in key.joints]
            sizes = [self.size[key] for key in own]
            starts = b + np.concatenate([[0], np.cumsum(sizes)]).astype(int)
            self.local.append({key: np.arange(starts[k], starts[k + 1]) for k, key in enumerate(own)})
            G, c, s = np.zeros((starts[-1], starts[-1])), np.zeros(starts[-1]), 0.0
            for lo in range(0, rows.size, CHUNK):  # the stacked columns of a chunk only: bounded memory
                part = rows[lo : lo + CHUNK]
                L = np.hstack([data.regressor[part * n + j]] + [key.rows(n)[j] * data.blocks[key][part] for key in own])
                tau = data.tau[part * n + j]
                if scale is not None:
                    L, tau = L * scale[part, j, None], tau * scale[part, j]
                G += L.T @ L
                c += L.T @ tau
                s += float(tau @ tau)
            self.G.append(G)
            self.c.append(c)
            self.s.append(s)

    def columns(self, effects: list[Term]) -> int:
        """Number of unknowns of the model [Y_B, ``effects``]."""
        return self.b + sum(self.size[t] for t in effects)

    def nonnegative(self, effects: list[Term]) -> np.ndarray:
        """(m,) which unknowns of the model [Y_B, ``effects``] are kept ≥ 0 (``NONNEGATIVE``)."""
        sizes = [self.size[t] for t in effects]
        return np.concatenate([np.zeros(self.b, dtype=bool), nonnegative_columns(effects, sizes)])

    def _placement(self, effects: list[Term]) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per joint j, (indices in j's local pieces, indices among the model's unknowns) of the base
        parameters and of the effects in the model [Y_B, ``effects``] that touch j's rows."""
        base = np.arange(self.b)
        local, glob = [[base] for _ in range(self.n)], [[base] for _ in range(self.n)]
        start = self.b
        for t in effects:
            for j in t.joints:
                local[j].append(self.local[j][t])
                glob[j].append(np.arange(start, start + self.size[t]))
            start += self.size[t]
        return [(np.concatenate(l), np.concatenate(g)) for l, g in zip(local, glob)]

    def system(self, weights: np.ndarray | None, effects: list[Term]) -> tuple[np.ndarray, np.ndarray, float]:
        """(G, c, s) of the model [Y_B, ``effects``] (unknowns in that order) with joint weights (n,)."""
        m = self.columns(effects)
        G, c, s = np.zeros((m, m)), np.zeros(m), 0.0
        for j, (local, glob) in enumerate(self._placement(effects)):
            w2 = 1.0 if weights is None else float(weights[j]) ** 2
            G[np.ix_(glob, glob)] += w2 * self.G[j][np.ix_(local, local)]
            c[glob] += w2 * self.c[j][local]
            s += w2 * self.s[j]
        return G, c, s

    def stacked(self, keys: list[Term]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per-joint pieces placed in the unknowns of the model [Y_B, every one of ``keys``]:
        G (n, P, P), c (n, P), s (n,) (unweighted), so that any smaller model's system is a
        weighted sum over joints and a selection of rows and columns."""
        size = self.columns(keys)
        G, c = np.zeros((self.n, size, size)), np.zeros((self.n, size))
        for j, (local, glob) in enumerate(self._placement(keys)):
            G[j][np.ix_(glob, glob)] = self.G[j][np.ix_(local, local)]
            c[j, glob] = self.c[j][local]
        return G, c, np.array(self.s)

    def joint_sse(self, x: np.ndarray, effects: list[Term]) -> np.ndarray:
        """(n,) unweighted residual sum of squares of each joint [Nm²] for coefficients x."""
        out = np.zeros(self.n)
        for j, (local, glob) in enumerate(self._placement(effects)):
            xj = x[glob]
            G = self.G[j][np.ix_(local, local)]
            out[j] = max(self.s[j] - 2.0 * xj @ self.c[j][local] + xj @ G @ xj, 0.0)
        return out


def _unit_diagonal(G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """G scaled to unit diagonal, D⁻¹GD⁻¹, and the scales d = sqrt(diag G) (1 where 0)."""
    d = np.sqrt(np.diag(G))
    d[d == 0] = 1.0
    return G / np.outer(d, d), d


def solve(G: np.ndarray, c: np.ndarray, nonnegative: np.ndarray | None = None) -> np.ndarray:
    """x of G x = c, columns scaled to unit diagonal (minimum-norm where G is singular): the least
    squares of normal equations G (m, m), c (m,). With ``nonnegative`` (m,) (a mask), the least squares
    with those unknowns ≥ 0 where the plain solution has one below 0 (:func:`_bounded`)."""
    scaled, d = _unit_diagonal(G)
    z = _solver(scaled)(c / d)
    if nonnegative is not None and np.any(z[nonnegative] < 0.0):
        z = _bounded(scaled, c / d, np.asarray(nonnegative, dtype=bool))
    return z / d


def _solver(G: np.ndarray):
    """y ↦ G⁻¹ y (y (m,) or (m, k)) for G scaled to unit diagonal: 0 for the unknowns whose column the
    data never see (a held-out run's offset in a fold: a zero row and column), Cholesky for the rest,
    or the pseudo-inverse where that is singular too (each the minimum-norm solution).

    Singular means Cholesky fails or finishes with a pivot below :data:`ROUNDING` × the largest: a dependent
    column's pivot is rounding, and whether Cholesky accepts it depends on the order of the sums (the
    number of BLAS threads), so it would give huge coefficients on one machine and the minimum-norm
    ones on another (Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed., 2002, ch. 10)."""
    seen = np.diag(G) > 0.0
    try:
        factor = scipy.linalg.cho_factor(G[np.ix_(seen, seen)])
        pivots = np.diag(factor[0]) ** 2
        if pivots.size and pivots.min() <= ROUNDING * pivots.max():
            raise np.linalg.LinAlgError("a pivot is rounding")
    except np.linalg.LinAlgError:
        inverse = np.linalg.pinv(G, rcond=ROUNDING, hermitian=True)
        return lambda y: inverse @ y

    def apply(y: np.ndarray) -> np.ndarray:
        out = np.zeros(y.shape)
        out[seen] = scipy.linalg.cho_solve(factor, y[seen])
        return out

    return apply


def _bounded(G: np.ndarray, c: np.ndarray, bounded: np.ndarray) -> np.ndarray:
    """argmin ½xᵀGx − cᵀx (G (m, m) scaled to unit diagonal) with x_i ≥ 0 where ``bounded``: the free
    unknowns F eliminated for given bounded ones B (x_F = G_FF⁻¹(c_F − G_FB x_B)), the rest is
    ½x_BᵀSx_B − rᵀx_B, S the Schur complement G_BB − G_BF G_FF⁻¹ G_FB, r = c_B − G_BF G_FF⁻¹ c_F: a
    non-negative least squares (:func:`_nonnegative_least_squares`; Lawson & Hanson, Solving Least
    Squares Problems, 1974, ch. 23; scipy's ``nnls``)."""
    free = ~bounded
    solve_free = _solver(G[np.ix_(free, free)])
    K = solve_free(G[np.ix_(free, bounded)])  # G_FF⁻¹ G_FB
    S = G[np.ix_(bounded, bounded)] - G[np.ix_(bounded, free)] @ K
    x = np.zeros(c.size)
    x[bounded] = _nonnegative_least_squares(0.5 * (S + S.T), c[bounded] - K.T @ c[free])
    x[free] = solve_free(c[free] - G[np.ix_(free, bounded)] @ x[bounded])
    return x


def _nonnegative_least_squares(S: np.ndarray, r: np.ndarray) -> np.ndarray:
    """argmin ½xᵀSx − rᵀx with x ≥ 0 (S (k, k) a Schur complement of a unit-diagonal G, r (k,)), as
    the non-negative least squares ‖Ax − b‖² with AᵀA = S, Aᵀb = r. S_ii is the share of column i
    outside the span of the columns eliminated: below :data:`ROUNDING` it is rounding (or the data never see
    the column) and x_i is held at 0, where dividing by that rounding would give any value."""
    x = np.zeros(r.size)
    live = np.diag(S) > ROUNDING
    if not live.any():
        return x
    S, r = S[np.ix_(live, live)], r[live]
    try:
        L = np.linalg.cholesky(S)  # S = L Lᵀ: A = Lᵀ, b = L⁻¹ r
        if np.diag(L).min() ** 2 <= ROUNDING:
            raise np.linalg.LinAlgError("a pivot is rounding")
        A, b = L.T, scipy.linalg.solve_triangular(L, r, lower=True)
    except np.linalg.LinAlgError:  # S singular: its directions below ROUNDING dropped
        A, b = square_root(S, r, floor=ROUNDING)
    if A.shape[0]:
        x[live] = scipy.optimize.nnls(A, b)[0]
    return x


def square_root(G: np.ndarray, c: np.ndarray, floor: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A (k, m), b (k,) with AᵀA = G and Aᵀb = c for normal equations G (m, m) (symmetric positive
    semidefinite), c (m,): ‖Ax − b‖² = xᵀGx − 2cᵀx + const, a least-squares form of them, from the
    eigenpairs of G with eigenvalues above :data:`ROUNDING` × the largest and above ``floor`` (k of them; the
    rest, directions G does not see, dropped)."""
    eigenvalues, vectors = np.linalg.eigh(G)
    kept = eigenvalues > max(ROUNDING * max(eigenvalues[-1], 1e-300), floor)
    roots = np.sqrt(eigenvalues[kept])
    return roots[:, None] * vectors[:, kept].T, (vectors[:, kept].T @ c) / roots


def excited_rank(G: np.ndarray, tolerance: float = 1e-12) -> int:
    """Number of unknowns the data determine: the rank of G scaled to unit diagonal (eigenvalues above
    ``tolerance`` × the largest; a column the data never excite counts as rank loss)."""
    scaled, _ = _unit_diagonal(G)
    eig = np.linalg.eigvalsh(scaled)
    return int(np.sum(eig > tolerance * max(eig[-1], 0.0))) if eig.size and eig[-1] > 0 else 0


def sse(G: np.ndarray, c: np.ndarray, s: float, x: np.ndarray) -> float:
    """Residual sum of squares s − 2xᵀc + xᵀGx (≥ 0)."""
    return max(s - 2.0 * x @ c + x @ G @ x, 0.0)


def outside_fraction(G: np.ndarray, model: int) -> float:
    """Fraction of the squared norm of the last columns (after the first ``model``) outside the span
    of the first ones: the Schur complement's trace over the block's, with unit-diagonal scaling."""
    scaled, _ = _unit_diagonal(G)
    S, C, SC = scaled[:model, :model], scaled[model:, model:], scaled[:model, model:]
    inside = SC.T @ np.linalg.lstsq(S, SC, rcond=ROUNDING)[0]
    return float(np.trace(C - inside) / max(np.trace(C), 1e-300))


def covariance_diagonal(G: np.ndarray, middle: np.ndarray | None = None) -> np.ndarray:
    """diag(G⁻¹), or of the sandwich G⁻¹ M G⁻¹ with ``middle`` M (the same size as G), with
    unit-diagonal scaling."""
    scaled, d = _unit_diagonal(G)
    inverse = np.linalg.pinv(scaled, rcond=ROUNDING, hermitian=True)
    if middle is None:
        return np.diag(inverse) / d**2
    return np.einsum("ij,jk,ki->i", inverse, middle / np.outer(d, d), inverse) / d**2


def weighted_fit(data: Dataset, effects: list[Term], scale: np.ndarray) -> np.ndarray:
    """x (b + Σk,) of the model [Y_B, ``effects``] fitted by least squares to ``data`` with each
    instant's row of each joint weighed by ``scale`` (N, n) (generalized least squares with a diagonal
    noise covariance, the weights 1/σ of each sample; friction and armature kept ≥ 0 as in every fit)."""
    normal = NormalEquations(data, effects, scale=scale)
    G, c, _ = normal.system(None, effects)
    return solve(G, c, normal.nonnegative(effects))
