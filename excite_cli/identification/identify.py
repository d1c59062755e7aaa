"""Base parameters by (weighted) least squares (Eq. 4), and the loop that traces the residual to the
effects the rigid-body model lacks.

Weighted least squares follows Gautier (1997): each joint's rows are weighted by 1/σ_j, σ_j the
residual standard deviation of that joint under ordinary least squares of the rigid-body model,
fixed for the whole selection and the final fit (so the reported model is the one that was
scored); the estimates' standard
deviations come from σ² (AᵀWA)⁻¹, scaled by √r: after the parallel low-pass at f_c, samples at
f_s carry only about 2 f_c T independent values (r = f_s / (2 f_c), the oversampling), and the
F-test below counts its degrees of freedom the same way.

Effect selection is forward: at each step every remaining candidate block (effect, joint) is
added to the current model in turn and ranked by the held-out (validation) weighted error; the
first in that order is kept that (1) lowers it by at least ``min_improvement`` (a fraction, default
1 %: with tens of thousands of rows a test alone finds sub-milli-newton-metre artefacts
significant) and (2) passes an F-test for nested linear models on the fit data, rejecting "no
effect" at ``significance`` divided by the number of candidates tried (Bonferroni). A candidate
that fails the test does not end the search while lower-ranked ones pass both.
Candidates whose columns lie in the span of the current model are not identifiable separately and
are skipped. The loop stops when no candidate passes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from scipy import stats

from excite_cli.base_parameters import BaseParameters
from excite_cli.config import IdentificationConfig
from excite_cli.identification.effects import COEFFICIENTS, REQUIRES, TWO_STAGE, effect_columns
from excite_cli.identification.preprocessing import Samples
from excite_cli.robot import Robot

EFFECTS = tuple(COEFFICIENTS)

#: A candidate whose columns keep less than this fraction of their norm outside the current model's
#: span is not identifiable separately.
IDENTIFIABILITY = 1e-6


@dataclass(frozen=True)
class Dataset:
    """Stacked, parallel-filtered and decimated samples: rows ordered by instant, then joint.

    Attributes:
        regressor: (N·n, b) base regressor Y_B (Eq. 3).
        tau: (N·n,) measured torques [Nm].
        time: (N,) [s]; run: (N,) index of the run of each instant.
        blocks: effect columns by (effect, joint index), (N, k) each, on that joint's rows.
    """

    regressor: np.ndarray
    tau: np.ndarray
    time: np.ndarray
    run: np.ndarray
    blocks: dict[tuple[str, int], np.ndarray]

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.tau.size // self.time.size

    @property
    def joint(self) -> np.ndarray:
        """(N·n,) joint index of each row."""
        return np.tile(np.arange(self.n), self.time.size)

    def block(self, effect: str, j: int) -> np.ndarray:
        """(N·n, k) columns of ``effect`` on joint j: nonzero only on joint j's rows."""
        cols = self.blocks[(effect, j)]
        out = np.zeros((self.tau.size, cols.shape[1]))
        out[j :: self.n] = cols
        return out

    def with_load_columns(self, base_parameters: np.ndarray) -> "Dataset":
        """The dataset with the two-stage ``load_coulomb`` blocks: abs(τ_rigid) times the Coulomb
        block, τ_rigid = Y_B φ_B with the base parameters (b,) of a first, rigid-body fit (the product
        of the filtered signals stands for the filtered product: both vary slowly at the cut-off)."""
        rigid = np.abs(self.regressor @ base_parameters).reshape(-1, self.n)
        extra = {("load_coulomb", j): rigid[:, j:j + 1] * self.blocks[("coulomb", j)] for j in range(self.n)}
        return Dataset(self.regressor, self.tau, self.time, self.run, {**self.blocks, **extra})

    def select(self, mask: np.ndarray) -> "Dataset":
        """The instants where ``mask`` (N,) is true."""
        rows = np.repeat(mask, self.n)
        return Dataset(self.regressor[rows], self.tau[rows], self.time[mask], self.run[mask],
                       {key: cols[mask] for key, cols in self.blocks.items()})


def build_dataset(robot: Robot, base: BaseParameters, samples: list[Samples], cfg: IdentificationConfig) -> Dataset:
    """Regressor, candidate effect columns and torques of the samples, each low-passed by its run's
    filter in parallel and decimated (so the filtered τ still equals the filtered columns × φ)."""
    n, b = robot.n_joints, base.count
    X = base.composition_matrix
    parts = []
    for index, s in enumerate(samples):
        # the base regressor at the run's rate is (T·n, b): computed, filtered and decimated in chunks
        Y = s.filter.decimate_chunks(lambda lo, hi: (robot.regressor_stack(s.q[lo:hi], s.qd[lo:hi], s.qdd[lo:hi]) @ X)
                                     .reshape(-1, n * b), s.time.size)
        blocks = {
            (e, j): s.filter.decimate(effect_columns(e, s.q[:, j], s.qd[:, j], s.qdd[:, j], cfg.coulomb_velocity,
                                                     cfg.stribeck_velocity, cfg.held_velocity))
            for e in EFFECTS if e not in TWO_STAGE for j in range(n)
        }
        time = s.time[s.filter.trim : s.time.size - s.filter.trim : s.filter.step]
        parts.append((Y.reshape(-1, b), s.filter.decimate(s.tau).ravel(), time, np.full(time.size, index), blocks))
    return Dataset(
        np.vstack([p[0] for p in parts]),
        np.concatenate([p[1] for p in parts]),
        np.concatenate([p[2] for p in parts]),
        np.concatenate([p[3] for p in parts]),
        {key: np.vstack([p[4][key] for p in parts]) for key in parts[0][4]},
    )


@dataclass(frozen=True)
class Fit:
    """A least-squares fit.

    Attributes:
        x: (p,) estimates; std: (p,) their standard deviations.
        sigma: (n,) per-joint residual standard deviation [Nm] of this fit.
    """

    x: np.ndarray
    std: np.ndarray
    sigma: np.ndarray


def _joint_sigma(residual: np.ndarray, joint: np.ndarray, n: int, p: int) -> np.ndarray:
    dof = max(1.0, residual.size - p) / residual.size
    return np.array([np.sqrt(np.mean(residual[joint == j] ** 2) / dof) for j in range(n)])


def least_squares(A: np.ndarray, y: np.ndarray, joint: np.ndarray, n: int, weights: np.ndarray | None = None,
                  oversampling: float = 1.0) -> Fit:
    """Ordinary (Eq. 4) or weighted least squares of y ≈ A x with standard deviations.

    Args:
        A: (M, p) design matrix; y: (M,) torques; joint: (M,) joint of each row; n: joints.
        weights: (n,) weight of each joint's rows (WLS, see :func:`joint_weights`), or None (LS).
        oversampling: samples per independent sample (r ≥ 1); the deviations are scaled by √r.
    """
    scale = np.linalg.norm(A, axis=0)
    scale[scale == 0] = 1.0
    w = np.ones_like(y) if weights is None else weights[joint]
    Q, R = np.linalg.qr(w[:, None] * A / scale)
    x = scipy.linalg.solve_triangular(R, Q.T @ (w * y)) / scale
    sigma = _joint_sigma(y - A @ x, joint, n, A.shape[1])
    residual = w * (y - A @ x)
    s2 = residual @ residual / max(1, y.size - A.shape[1])
    Rinv = scipy.linalg.solve_triangular(R, np.eye(R.shape[0]))
    std = np.sqrt(oversampling * s2 * np.sum(Rinv**2, axis=1)) / scale
    return Fit(x, std, sigma)


def joint_weights(data: Dataset, weighted: bool) -> np.ndarray | None:
    """(n,) WLS weights 1/σ_j, σ_j the rigid-body least-squares residual of joint j (Gautier 1997),
    or None for LS. Fixed for the whole selection and the final fit, so the reported model is the
    one the selection scored."""
    if not weighted:
        return None
    sigma = least_squares(data.regressor, data.tau, data.joint, data.n).sigma
    return 1.0 / np.maximum(sigma, 1e-12)


@dataclass
class Selection:
    """Outcome of the effect-selection loop.

    Attributes:
        effects: chosen (effect, joint) in order, the declared ones first.
        declared: how many of ``effects`` were declared in the config.
        fit: final fit of [Y_B, effect columns] (base parameters first).
        rigid: fit of the rigid-body model alone.
        steps: per added effect: validation weighted SSE after, F statistic, p-value.
        absorbed: candidates skipped as not separately identifiable (in the span of the model).
        weights: (n,) the joints' weights (WLS) or None (LS), the same in every fit.
    """

    effects: list[tuple[str, int]]
    declared: int
    fit: Fit
    rigid: Fit
    steps: list[dict] = field(default_factory=list)
    absorbed: list[tuple[str, int]] = field(default_factory=list)
    weights: np.ndarray | None = None


def design(data: Dataset, effects: list[tuple[str, int]]) -> np.ndarray:
    """[Y_B, effect blocks] (M, b + Σk)."""
    return np.hstack([data.regressor] + [data.block(e, j) for e, j in effects])


def _open(candidates: list[str], n: int, effects: list[tuple[str, int]]) -> list[tuple[str, int]]:
    """Candidates not in the model whose required effect (``REQUIRES``) is in it."""
    return [(e, j) for e in candidates for j in range(n)
            if (e, j) not in effects and (e not in REQUIRES or (REQUIRES[e], j) in effects)]


def select_effects(fit_data: Dataset, val_data: Dataset, cfg: IdentificationConfig,
                   declared: list[tuple[str, int]], oversampling: float = 1.0) -> Selection:
    """Forward selection of effects (module docstring); declared effects are in the model from the start.

    Args:
        oversampling: samples per independent sample r (≥ 1) of the filtered data.
    """
    n = fit_data.n
    weights = joint_weights(fit_data, cfg.method == "wls")
    rigid = least_squares(fit_data.regressor, fit_data.tau, fit_data.joint, n, weights, oversampling)
    val_w = 1.0 / np.maximum(rigid.sigma[val_data.joint], 1e-12)  # fixed, so errors compare across steps
    w = np.ones(fit_data.tau.size) if weights is None else weights[fit_data.joint]
    effects = list(declared)
    absorbed: set[tuple[str, int]] = set()
    selection = Selection(effects, len(declared), rigid, rigid, weights=weights)
    while len(effects) - len(declared) < cfg.max_effects:
        remaining = [c for c in _open(cfg.candidates, n, effects) if c not in absorbed]
        if not remaining:
            break
        A = design(fit_data, effects)
        scale = np.linalg.norm(A, axis=0)
        scale[scale == 0] = 1.0
        Q, R = np.linalg.qr(w[:, None] * A / scale)
        wy = w * fit_data.tau
        x0 = scipy.linalg.solve_triangular(R, Q.T @ wy)
        r0 = wy - Q @ (Q.T @ wy)
        sse0 = r0 @ r0
        A_val = design(val_data, effects) / scale
        base_prediction = A_val @ x0
        val0 = np.sum((val_w * (val_data.tau - base_prediction)) ** 2)
        tried = []
        for cand in remaining:
            j = cand[1]
            cols = w[j::n, None] * fit_data.blocks[cand]  # (N, k) on joint j's rows
            QtB = Q[j::n].T @ cols
            B_perp = -(Q @ QtB)
            B_perp[j::n] += cols
            if np.linalg.norm(B_perp) < IDENTIFIABILITY * np.linalg.norm(cols):
                absorbed.add(cand)
                continue
            c = np.linalg.solve(B_perp.T @ B_perp, B_perp.T @ r0)
            gain = r0 @ (B_perp @ c)
            prediction = base_prediction - A_val @ scipy.linalg.solve_triangular(R, QtB @ c)
            prediction[j::n] += val_data.blocks[cand] @ c
            val1 = np.sum((val_w * (val_data.tau - prediction)) ** 2)
            tried.append((val1, cand, gain, cols.shape[1]))
        chosen = None
        for val1, cand, gain, k in sorted(tried, key=lambda t: t[0]):  # best held-out error first
            if not val1 < (1.0 - cfg.min_improvement) * val0:
                break  # the rest gain less
            dof = (fit_data.tau.size - A.shape[1] - k) / oversampling
            F = (gain / k) / ((sse0 - gain) / dof)
            p = float(stats.f.sf(F, k, dof))
            if p < cfg.significance / len(remaining):  # a lower-ranked candidate may pass where the first fails
                chosen = {"effect": cand[0], "joint": cand[1], "validation_sse": float(val1), "F": float(F), "p": p}
                break
        if chosen is None:
            break
        effects.append((chosen["effect"], chosen["joint"]))
        selection.steps.append(chosen)
    selection.effects = effects
    selection.absorbed = sorted(absorbed)
    selection.fit = least_squares(design(fit_data, effects), fit_data.tau, fit_data.joint, n, weights, oversampling)
    return selection


def predict(data: Dataset, x: np.ndarray, effects: list[tuple[str, int]]) -> np.ndarray:
    """Predicted torques (N, n) [Nm] of the model [Y_B, effects] with coefficients x."""
    return (design(data, effects) @ x).reshape(-1, data.n)
