"""Blocked cross-validation of a model on the fit data, through normal equations per fold.

The fit instants of every run are cut into K contiguous time blocks; fold k holds out the k-th block
of every run at once (for runs cropped from the same periodic excitation, the same phase of the
period). Filtered samples are correlated over about one period of the cut-off, so the instants
within ``margin`` seconds of a held-out block are left out of that fold's fit: correlated samples
never sit on both sides. A model is fitted on the rest of the fit data and scored on the held-out
block, K times, and the error of every fit instant counts once:

    CV(M) = mean over joints j of  sqrt(Σ_k SSE_kj(M) / N) / RMS(τ_j)  × 100 %,

the same figure (mean relative RMS torque error) that the report gives on the validation data.
Every fold's normal equations are sums of per-joint pieces (:mod:`~excite_cli.identification.normal`),
so the training system of fold k is the total minus the block and its margin: a model costs K solves
of its own size, whatever the number of samples.
"""

from __future__ import annotations

import numpy as np

from excite_cli.identification.dataset import Dataset
from excite_cli.identification.effects import Term
from excite_cli.identification.normal import NormalEquations, solve


def fold_assignment(
    time: np.ndarray, run: np.ndarray, folds: int, margin: float
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Blocked folds of the fit instants.

    Args:
        time: (N,) [s] and run: (N,) run index of each instant, each run's instants in time order.
        folds: K.
        margin: [s] instants this close to a held-out block (same run) are left out of its fit.

    Returns:
        (N,) fold of each instant, and per fold a (N,) mask of its margin instants.
    """
    fold = np.empty(time.size, dtype=int)
    margins = [np.zeros(time.size, dtype=bool) for _ in range(folds)]
    for r in np.unique(run):
        idx = np.flatnonzero(run == r)
        fold[idx] = np.minimum(np.arange(idx.size) * folds // idx.size, folds - 1)
        t = time[idx]
        for k in range(folds):
            inside = fold[idx] == k
            if not inside.any():
                continue
            lo, hi = t[inside][0], t[inside][-1]
            margins[k][idx] = ~inside & (t >= lo - margin) & (t <= hi + margin)
    return fold, margins


class CrossValidation:
    """K-fold blocked cross-validation (module docstring) of models built from ``keys``.

    Every fold's per-joint normal equations are placed once in the unknowns of the largest model
    [Y_B, all ``keys``]; a model's systems are then selections of their rows and columns.

    Args:
        data: the fit data.
        keys: every term a model may contain.
        weights: (n,) the joints' weights (WLS) or None (LS), fixed for every model.
        folds: K (≥ 2).
        margin: [s] left out around each held-out block (about one period of the cut-off).
    """

    def __init__(self, data: Dataset, keys: list[Term], weights: np.ndarray | None, folds: int, margin: float):
        fold, margins = fold_assignment(data.time, data.run, folds, margin)
        self.b, self.n, self.instants = data.regressor.shape[1], data.n, data.time.size
        sizes = [data.blocks[key].shape[1] for key in keys]
        starts = self.b + np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        self.place = {key: np.arange(starts[k], starts[k + 1]) for k, key in enumerate(keys)}
        w2 = np.ones(self.n) if weights is None else np.asarray(weights, dtype=float) ** 2
        held = [NormalEquations(data, keys, np.flatnonzero(fold == k)).stacked(keys) for k in range(folds)]
        margin_parts = [NormalEquations(data, keys, np.flatnonzero(m)).stacked(keys) for m in margins]
        weighted = [(np.einsum("j,jab->ab", w2, G), w2 @ c) for G, c, _ in held]
        total_G, total_c = sum(G for G, _ in weighted), sum(c for _, c in weighted)
        self.train = [
            (total_G - G - np.einsum("j,jab->ab", w2, mG), total_c - c - w2 @ mc)
            for (G, c), (mG, mc, _) in zip(weighted, margin_parts)
        ]
        self.held = held
        measured = sum(s for _, _, s in held)
        self.rms = np.sqrt(measured / max(self.instants, 1))

    def unknowns(self, terms: list[Term]) -> np.ndarray:
        """Indices of the model [Y_B, ``terms``]'s unknowns among the largest model's."""
        return np.concatenate([np.arange(self.b)] + [self.place[t] for t in terms])

    def fold_sse(self, terms: list[Term]) -> np.ndarray:
        """(K, n) held-out residual sum of squares [Nm²] per fold and joint of the model [Y_B,
        ``terms``] fitted on the other folds minus the margin."""
        idx = self.unknowns(terms)
        out = np.zeros((len(self.held), self.n))
        for k, ((G, c), (Gj, cj, sj)) in enumerate(zip(self.train, self.held)):
            x = solve(G[np.ix_(idx, idx)], c[idx])
            quadratic = np.einsum("a,jab,b->j", x, Gj[:, idx][:, :, idx], x)
            out[k] = np.maximum(sj - 2.0 * cj[:, idx] @ x + quadratic, 0.0)
        return out

    def error(self, terms: list[Term]) -> tuple[float, np.ndarray]:
        """CV(M) [%] (module docstring) and the (n,) per-joint relative errors [%] of the model
        [Y_B, ``terms``]."""
        sse = self.fold_sse(terms).sum(axis=0)
        per_joint = 100.0 * np.sqrt(sse / max(self.instants, 1)) / np.where(self.rms > 0, self.rms, 1.0)
        return float(per_joint.mean()), per_joint
