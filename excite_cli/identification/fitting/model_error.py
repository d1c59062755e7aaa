"""The spread of the estimates between recordings of distinct trajectories: the model error's share
of the uncertainty, which no noise model of one recording holds.

A model that lacks an effect leaves a residual e(x) that is a function of the motion, not noise: two
recordings of the same trajectory share it (their estimates agree more closely than a noise-only
covariance says), two trajectories see different parts of it (their estimates differ by more). The
least-squares estimate's deviation is G⁻¹ Σ_g s_g with the score of each trajectory g,
s_g = Σ_{rows of g} w_j² a e (a the row of [Y_B, effects], W = w_j² on joint j's rows), and when the
fit holds G ≥ 3 distinct trajectories, the cluster-robust covariance

    V = G⁻¹ (Σ_g s_g s_gᵀ) G⁻¹

(Liang & Zeger, Biometrika 1986) estimates the spread over trajectories, model error and noise
together. With few trajectories the residuals of each are shrunk by its own pull on the fit: with
4, the plain form (CR1, times G/(G−1)) came out 25 % low and the jackknife over trajectories (CR3)
15–25 % high against the spread over sets of simulated trajectories (the test); each trajectory's
residuals are therefore taken through (I − H_gg)^(-1/2), H_gg its block of the hat matrix (CR2:
Bell & McCaffrey 2002; Imbens & Kolesár, Rev. Econ. Stat. 2016): a median 0.90–1.00 over the base
parameters (3 seeds). Its
standard deviations come from G − 1 degrees of freedom: with 3 or 4 trajectories each is known to
within a factor of about 1.5 either way; the recordings of one trajectory (recorded twice) are one
cluster, never two.

Fewer than 3 trajectories (one recording, the folds its time blocks): the same form with the time
blocks of the cross-validation as the groups, the k-th block of every run of one trajectory one group
(a cluster covariance over a few large blocks of dependent data: Bester, Conley & Hansen, J.
Econometrics 2011; its standard deviations from K − 1 degrees of freedom). It holds what the
noise's sandwich (:mod:`~excite_cli.identification.fitting.noise`) cannot: a residual that grows
and shrinks with the regressor's rows (model error is a function of the motion) and a slow drift.
On halves of one simulated recording of a non-repeating motion (a spring, a friction shape or a
drift the model lacks; ``bench/recording_halves.py``) this std of a half is 0.83–0.96 × the spread
between the halves (median over the base parameters), the sandwich's 0.69–0.83 ×. Where every block
holds the same motion (a periodic excitation recorded over whole periods) the model error is the
same in every block, so the halves agree more closely than either says."""

from __future__ import annotations

import numpy as np

from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import predict
from excite_cli.identification.fitting.normal import ROUNDING, covariance_diagonal

#: The fewest distinct trajectories the spread is estimated from (2 give scores s₁ = −s₂: one degree
#: of freedom).
FEWEST = 3
#: Instants of a trajectory taken at a time (memory: a (CHUNK, m) block per joint).
CHUNK = 1 << 16


def trajectory_pieces(
    data: Dataset, x: np.ndarray, effects: list[Term], weights: np.ndarray | None, cluster: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Each trajectory's share of the weighted normal matrix, G_g = Σ_{rows of g} w_j² a aᵀ (G, m, m),
    and its score s_g (G, m) (module docstring), of the model [Y_B, ``effects``] with coefficients x
    (m,) and joint weights (n,) (None: 1) on ``data``; ``cluster`` (R,) the trajectory of each run
    index of ``data.run``, the trajectories in ascending order."""
    return _pieces(data, x, effects, weights, cluster[data.run])


def _pieces(
    data: Dataset, x: np.ndarray, effects: list[Term], weights: np.ndarray | None, of_instant: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`trajectory_pieces` with the group of each instant (N,) given, groups in ascending order."""
    n = data.n
    residual = data.tau.reshape(-1, n) - predict(data, x, effects)
    w = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
    groups = np.unique(of_instant)
    grams, scores = np.zeros((groups.size, x.size, x.size)), np.zeros((groups.size, x.size))
    for k, g in enumerate(groups):
        instants = np.flatnonzero(of_instant == g)
        for rows in np.array_split(instants, -(-instants.size // CHUNK)):  # memory: CHUNK rows at a time
            for j in range(n):
                A = data.joint_rows(rows, j, effects)
                grams[k] += w[j] ** 2 * (A.T @ A)
                scores[k] += w[j] ** 2 * (A.T @ residual[rows, j])
    return grams, scores


def between_trajectories(
    data: Dataset, x: np.ndarray, effects: list[Term], weights: np.ndarray | None, cluster: np.ndarray
) -> np.ndarray | None:
    """(m,) the variances of the estimates over trajectories (module docstring, CR2) of the model
    [Y_B, ``effects``] fitted with coefficients x (m,) and joint weights (n,) (None: 1) on ``data``;
    ``cluster`` (R,) the trajectory of each run index of ``data.run``. None with fewer than
    ``FEWEST`` trajectories; NaN for a coefficient that the other trajectories cannot determine
    without one of them (a run's own offset)."""
    if np.unique(cluster[np.unique(data.run)]).size < FEWEST:
        return None
    return _variance(*trajectory_pieces(data, x, effects, weights, cluster), x.size)


def between_time_blocks(
    data: Dataset,
    x: np.ndarray,
    effects: list[Term],
    weights: np.ndarray | None,
    block: np.ndarray,
    cluster: np.ndarray,
) -> tuple[np.ndarray, int]:
    """(m,) the variances of the estimates over the time blocks of fewer than ``FEWEST`` trajectories
    (module docstring: CR2 by block; Bester, Conley & Hansen 2011) of the model [Y_B, ``effects``]
    fitted with coefficients x (m,) and joint weights (n,) (None: 1) on ``data``; ``block`` (N,) the
    time block of each instant within its run (the cross-validation's time-block folds), ``cluster``
    (R,) the trajectory of each run index: the k-th blocks of one trajectory's runs are one group. NaN
    for a coefficient that one group alone determines. Also returns the number of groups."""
    of_instant = cluster[data.run] * (int(block.max()) + 1) + block
    return _variance(*_pieces(data, x, effects, weights, of_instant), x.size), int(np.unique(of_instant).size)


def _variance(grams: np.ndarray, scores: np.ndarray, m: int) -> np.ndarray:
    """(m,) CR2 variances from each group's share of the normal matrix (G, m, m) and its score (G, m)
    (:func:`trajectory_pieces`); NaN where one group alone determines a coefficient."""
    total = grams.sum(axis=0)
    inverse = np.linalg.pinv(total, rcond=ROUNDING, hermitian=True)
    alone = np.zeros(m, dtype=bool)
    adjusted = np.zeros_like(scores)
    for k in range(len(grams)):
        alone |= np.diag(total - grams[k]) <= 1e-12 * np.diag(total)
        adjusted[k] = _leverage_adjusted(grams[k], scores[k], inverse)
    variance = covariance_diagonal(total, adjusted.T @ adjusted)
    return np.where(alone, np.nan, variance)


def _leverage_adjusted(gram: np.ndarray, score: np.ndarray, inverse: np.ndarray) -> np.ndarray:
    """Bᵀ(I − H)^(-1/2) e of one trajectory (B its weighted rows, e its residuals, H = B G⁻¹ Bᵀ its
    block of the hat matrix: CR2's residuals, Bell & McCaffrey, Survey Methodology 2002), from its
    m × m pieces alone: with B = Q R (RᵀR = BᵀB = ``gram``), H = Q K Qᵀ, K = R G⁻¹ Rᵀ, and
    Qᵀe = R⁻ᵀ s (``score`` s = Bᵀe), it is s + Rᵀ((I − K)^(-1/2) − I) R⁻ᵀ s. A direction only this
    trajectory determines (leverage 1: its own offset) is left as it is (its score there is 0)."""
    lam, V = np.linalg.eigh(gram)
    kept = lam > 1e-12 * max(lam[-1], 1e-300)
    R = np.sqrt(lam[kept])[:, None] * V[:, kept].T  # (r, m)
    K = R @ inverse @ R.T
    mu, U = np.linalg.eigh((K + K.T) / 2.0)
    factor = np.where(mu < 1.0 - 1e-6, 1.0 / np.sqrt(np.maximum(1.0 - mu, 1e-300)), 1.0) - 1.0
    projected = (V[:, kept].T @ score) / np.sqrt(lam[kept])  # R⁻ᵀ s
    return score + R.T @ (U @ (factor * (U.T @ projected)))
