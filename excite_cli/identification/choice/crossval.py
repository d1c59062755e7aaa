"""Cross-validation of a model on the fit data, through normal equations per fold.

**Whole recordings** when the fit data come from two or more recordings (files): fold k holds out
recording k, every run cropped from it at once (leave one recording out; beyond :data:`RECORDING_FOLDS`
recordings, a fold holds out several consecutive ones), so the error estimates how
a model fitted on some recordings holds on another, with its own motion, load and temperature, which
is what a validation recording asks. Crops of one recording share all of that (for a periodic
excitation even the phases they cover), so they are one fold. Each run's offset is its own, and a
held-out run's is what the report would use on it: with ``fitted_offsets`` (every validation run is
also fitted, so the report knows its offset) it is fitted to the held-out run, one constant per
joint; otherwise the mean of the training runs' offsets, as a run the fit never saw gets in the
report (:func:`~excite_cli.identification.fitting.dataset.run_offset_columns`).

**Time blocks** for a single recording: the fit instants of every run are cut into K contiguous
time blocks; fold k holds out the k-th block
of every run at once (for runs cropped from the same periodic excitation, the same phase of the
period). Filtered samples are correlated over about one period of the cut-off, so the instants
within ``margin`` seconds of a held-out block are left out of that fold's fit: correlated samples
never sit on both sides. A model is fitted on the rest of the fit data and scored on the held-out
block, K times, and the error of every fit instant counts once:

    CV(M) = mean over joints j of  sqrt(Σ_k SSE_kj(M) / N) / RMS(τ_j)  × 100 %,

the same figure (mean relative RMS torque error) that the report gives on the validation data.
Every fold's normal equations are sums of per-joint pieces (:mod:`~excite_cli.identification.fitting.normal`),
so the training system of fold k is the total minus the block and its margin: a model costs K solves
of its own size, whatever the number of samples.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from excite_cli.errors import ExciteError
from excite_cli.identification.data_config import RunConfig
from excite_cli.identification.effects import Term, nonnegative_columns
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.normal import NormalEquations, solve

#: The most folds of whole recordings: more recordings are dealt into this many folds of consecutive
#: ones (10-fold cross-validation, Kohavi 1995), so that a model's score costs the same number of
#: solves from 10 recordings on (100 recordings of 2.5 s were 100 folds, and no output for 900 s).
RECORDING_FOLDS = 10


def fold_assignment(
    time: np.ndarray, run: np.ndarray, folds: int, margin: float, recording: np.ndarray | None = None
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Folds of the fit instants (module docstring).

    Args:
        time: (N,) [s] and run: (N,) run index of each instant, each run's instants in time order.
        folds: K (time blocks).
        margin: [s] instants this close to a held-out block (same run) are left out of its fit.
        recording: (N,) recording of each instant: one fold per recording (in their sorted order; more
            than :data:`RECORDING_FOLDS` recordings are dealt into that many folds of consecutive ones),
            no margins, instead of time blocks.

    Returns:
        (N,) fold of each instant, and per fold a (N,) mask of its margin instants.
    """
    if recording is not None:
        recordings, rank = np.unique(recording, return_inverse=True)
        count = min(recordings.size, RECORDING_FOLDS)
        fold = rank * count // recordings.size  # consecutive recordings together, at most RECORDING_FOLDS folds
        return fold, [np.zeros(time.size, dtype=bool) for _ in range(count)]
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
    """K-fold cross-validation (module docstring) of models built from ``keys``: whole recordings when
    the fit data come from two or more, else time blocks.

    Every fold's per-joint normal equations are placed once in the unknowns of the largest model
    [Y_B, all ``keys``]; a model's systems are then selections of their rows and columns.

    Args:
        data: the fit data.
        keys: every term a model may contain.
        weights: (n,) the joints' weights (WLS) or None (LS), fixed for every model.
        folds: K (≥ 2) of time blocks (a single recording).
        margin: [s] left out around each held-out block (about one period of the cut-off).
        recordings: recording of each run (indexed by ``data.run``): one fold per recording when they
            are two or more; None: time blocks.
        fitted_offsets: in recording folds, fit a held-out run's offsets to it instead of giving it
            the mean of the training runs' (module docstring).
        scored: (n,) the joints CV(M) is the mean over (default all; a torque channel without signal
            is not scored).

    Attributes:
        by_recording: whether the folds are whole recordings; folds: their number.
    """

    def __init__(
        self,
        data: Dataset,
        keys: list[Term],
        weights: np.ndarray | None,
        folds: int,
        margin: float,
        recordings: np.ndarray | None = None,
        fitted_offsets: bool = False,
        scored: np.ndarray | None = None,
    ):
        runs = np.unique(data.run)
        recording = None if recordings is None else np.asarray(recordings)[data.run]
        self.by_recording = recording is not None and np.unique(recording).size >= 2
        fold, margins = fold_assignment(data.time, data.run, folds, margin, recording if self.by_recording else None)
        self.folds, self.fitted_offsets = len(margins), fitted_offsets
        self.run_fold = fold[np.searchsorted(data.run, runs)] if self.by_recording else None  # (runs,)
        self.b, self.n, self.instants = data.regressor.shape[1], data.n, data.time.size
        self.scored = np.ones(self.n, dtype=bool) if scored is None or not np.any(scored) else np.asarray(scored)
        sizes = [data.blocks[key].shape[1] for key in keys]
        starts = self.b + np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        self.place = {key: np.arange(starts[k], starts[k + 1]) for k, key in enumerate(keys)}
        self.bounded = dict(zip(keys, np.split(nonnegative_columns(keys, sizes), np.cumsum(sizes)[:-1])))
        w2 = np.ones(self.n) if weights is None else np.asarray(weights, dtype=float) ** 2
        held = [NormalEquations(data, keys, np.flatnonzero(fold == k)).stacked(keys) for k in range(self.folds)]
        margin_parts = [NormalEquations(data, keys, np.flatnonzero(m)).stacked(keys) for m in margins]
        weighted = [(np.einsum("j,jab->ab", w2, G), w2 @ c) for G, c, _ in held]
        total_G, total_c = sum(G for G, _ in weighted), sum(c for _, c in weighted)
        self.train = [
            (total_G - G - np.einsum("j,jab->ab", w2, mG), total_c - c - w2 @ mc)
            for (G, c), (mG, mc, _) in zip(weighted, margin_parts)
        ]
        self.train_rows = [int(np.sum((fold != k) & ~m)) * self.n for k, m in enumerate(margins)]
        self.fold_instants = np.bincount(fold, minlength=self.folds)  # (K,) instants each fold holds out
        self.held = held
        measured = sum(s for _, _, s in held)
        self.rms = np.sqrt(measured / max(self.instants, 1))

    def unknowns(self, terms: list[Term]) -> np.ndarray:
        """Indices of the model [Y_B, ``terms``]'s unknowns among the largest model's."""
        return np.concatenate([np.arange(self.b)] + [self.place[t] for t in terms])

    def _offset_positions(self, terms: list[Term]) -> list[tuple[int, np.ndarray]]:
        """(joint, positions among the model [Y_B, ``terms``]'s unknowns of its per-run columns) of
        each offset term with one column per run."""
        out, start = [], self.b
        for t in terms:
            size = self.place[t].size
            if t.kind.per_run and self.run_fold is not None and size == self.run_fold.size:
                out.append((t.joint, np.arange(start, start + size)))
            start += size
        return out

    def nonnegative(self, terms: list[Term]) -> np.ndarray:
        """Which unknowns of the model [Y_B, ``terms``] every fit keeps ≥ 0 (friction, armature)."""
        return np.concatenate([np.zeros(self.b, dtype=bool)] + [self.bounded[t] for t in terms])

    def training_system(self, k: int, terms: list[Term]) -> tuple[np.ndarray, np.ndarray, int]:
        """Fold k's weighted training normal equations G (P, P), c (P,) of the model [Y_B, ``terms``]
        and the number of rows behind them: what any fit of fold k is fitted to."""
        idx = self.unknowns(terms)
        G, c = self.train[k]
        return G[np.ix_(idx, idx)], c[idx], self.train_rows[k]

    def fold_sse(self, terms: list[Term], refit: Callable[[int], np.ndarray] | None = None) -> np.ndarray:
        """(K, n) held-out residual sum of squares [Nm²] per fold and joint of the model [Y_B,
        ``terms``] fitted on the other folds minus the margin: by least squares, or by ``refit(k)``,
        which returns the model's coefficients fitted to :meth:`training_system` ``(k, terms)``."""
        idx = self.unknowns(terms)
        offsets = self._offset_positions(terms)
        out = np.zeros((len(self.held), self.n))
        bounded = self.nonnegative(terms)
        for k, (Gj, cj, sj) in enumerate(self.held):
            if refit is None:
                x = solve(*self.training_system(k, terms)[:2], bounded)
            else:
                x = np.array(refit(k), dtype=float)
            held_G, held_c = Gj[:, idx][:, :, idx], cj[:, idx]
            for j, columns in offsets:  # the held-out runs' offsets (module docstring)
                out_of_fit = self.run_fold == k
                x[columns[out_of_fit]] = 0.0 if self.fitted_offsets else x[columns[~out_of_fit]].mean()
                for p in columns[out_of_fit] if self.fitted_offsets else []:  # disjoint rows: one at a time
                    if held_G[j, p, p] > 0.0:
                        x[p] = (held_c[j, p] - held_G[j, p] @ x) / held_G[j, p, p]
            quadratic = np.einsum("a,jab,b->j", x, held_G, x)
            out[k] = np.maximum(sj - 2.0 * held_c @ x + quadratic, 0.0)
        return out

    def error(self, terms: list[Term], refit: Callable[[int], np.ndarray] | None = None) -> tuple[float, np.ndarray]:
        """CV(M) [%] (module docstring) and the (n,) per-joint relative errors [%] of the model
        [Y_B, ``terms``], fitted by least squares or ``refit`` (:meth:`fold_sse`)."""
        score = self.score(terms, refit)
        return score[0], score[1]

    def score(
        self, terms: list[Term], refit: Callable[[int], np.ndarray] | None = None
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """CV(M) [%], the (n,) per-joint errors [%] (:meth:`error`) and the (K,) error of each fold
        [%]: the mean over the scored joints of √(SSE_kj / N_k) / RMS(τ_j), N_k the fold's instants
        (what a paired test over folds compares, :mod:`~excite_cli.identification.choice.admission`)."""
        fold_sse = self.fold_sse(terms, refit)
        rms = np.where(self.rms > 0, self.rms, 1.0)
        per_joint = 100.0 * np.sqrt(fold_sse.sum(axis=0) / max(self.instants, 1)) / rms
        per_fold = 100.0 * np.sqrt(fold_sse / np.maximum(self.fold_instants, 1)[:, None]) / rms
        return float(per_joint[self.scored].mean()), per_joint, per_fold[:, self.scored].mean(axis=1)


def fold_groups(trajectories: np.ndarray, runs: list[RunConfig], how: str, fitted: list[int]) -> np.ndarray | None:
    """The cross-validation's groups (:class:`CrossValidation`) of ``identification.folds_by``
    (``how``): the trajectory of each configured run (``trajectories`` (R,): a recording, its crops and
    the recordings of the same motion together, :mod:`~excite_cli.identification.measured.twins`;
    held out apart, the model error they share would be seen in training), each run its own group,
    or None for time blocks. ``auto``: trajectories when the fit runs (indices ``fitted``) hold two
    or more, else time blocks.

    Raises:
        ExciteError: ``recording`` or ``run`` folds with fewer than two fit trajectories or runs.
    """
    groups = {"auto": trajectories, "recording": trajectories, "run": np.arange(len(runs)), "time_block": None}[how]
    count = 0 if groups is None else np.unique(groups[fitted]).size
    if how == "auto":
        return groups if count >= 2 else None
    if groups is not None and count < 2:
        raise ExciteError(
            "identification.folds_by",
            f"{how} folds need fit data from two or more {how}s; the fit data come from {count}",
            how,
            "time_block or auto",
        )
    return groups
