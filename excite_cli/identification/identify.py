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
are skipped. The loop stops when no candidate passes. Every fit goes through the per-joint normal
equations of :mod:`excite_cli.identification.normal` (no design matrix is formed).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from excite_cli.identification.config import IdentificationConfig
from excite_cli.identification.dataset import Dataset
from excite_cli.identification.effects import REQUIRES
from excite_cli.identification.normal import ABSORBED, NormalEquations, covariance_diagonal, outside_fraction, solve, sse


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


def least_squares(normal: NormalEquations, effects: list[tuple[str, int]], weights: np.ndarray | None = None,
                  oversampling: float = 1.0) -> Fit:
    """Ordinary (Eq. 4) or weighted least squares of the model [Y_B, ``effects``] with standard
    deviations σ² diag((AᵀWA)⁻¹), scaled by √r.

    Args:
        normal: the data's normal equations.
        weights: (n,) weight of each joint's rows (WLS, see :func:`joint_weights`), or None (LS).
        oversampling: samples per independent sample (r ≥ 1).
    """
    G, c, s = normal.system(weights, effects)
    x = solve(G, c)
    dof = max(1, normal.rows - x.size)
    s2 = sse(G, c, s, x) / dof
    std = np.sqrt(oversampling * s2 * np.maximum(covariance_diagonal(G), 0.0))
    sigma = np.sqrt(normal.joint_sse(x, effects) / (normal.rows / normal.n) / (dof / normal.rows))
    return Fit(x, std, sigma)


def joint_weights(normal: NormalEquations, weighted: bool) -> np.ndarray | None:
    """(n,) WLS weights 1/σ_j, σ_j the rigid-body least-squares residual of joint j (Gautier 1997),
    or None for LS. Fixed for the whole selection and the final fit, so the reported model is the
    one the selection scored."""
    if not weighted:
        return None
    return 1.0 / np.maximum(least_squares(normal, []).sigma, 1e-12)


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
    keys = list(fit_data.blocks)
    fit_ne, val_ne = NormalEquations(fit_data, keys), NormalEquations(val_data, keys)
    weights = joint_weights(fit_ne, cfg.method == "wls")
    rigid = least_squares(fit_ne, [], weights, oversampling)
    val_w = 1.0 / np.maximum(rigid.sigma, 1e-12)  # fixed, so errors compare across steps
    effects = list(declared)
    absorbed: set[tuple[str, int]] = set()
    selection = Selection(effects, len(declared), rigid, rigid, weights=weights)
    while len(effects) - len(declared) < cfg.max_effects:
        remaining = [c for c in _open(cfg.candidates, n, effects) if c not in absorbed]
        if not remaining:
            break
        G, c, s = fit_ne.system(weights, effects)
        x0 = solve(G, c)
        sse0 = sse(G, c, s, x0)
        val0 = sse(*val_ne.system(val_w, effects), x0)
        tried = []
        for cand in remaining:
            G1, c1, s1 = fit_ne.system(weights, effects + [cand])
            if outside_fraction(G1, G.shape[0]) < ABSORBED:
                absorbed.add(cand)
                continue
            x1 = solve(G1, c1)
            val1 = sse(*val_ne.system(val_w, effects + [cand]), x1)
            tried.append((val1, cand, sse0 - sse(G1, c1, s1, x1), G1.shape[0] - G.shape[0]))
        chosen = None
        for val1, cand, gain, k in sorted(tried, key=lambda t: t[0]):  # best held-out error first
            if not val1 < (1.0 - cfg.min_improvement) * val0:
                break  # the rest gain less
            dof = (fit_ne.rows - G.shape[0] - k) / oversampling
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
    selection.fit = least_squares(fit_ne, effects, weights, oversampling)
    return selection


def predict(data: Dataset, x: np.ndarray, effects: list[tuple[str, int]]) -> np.ndarray:
    """Predicted torques (N, n) [Nm] of the model [Y_B, effects] with coefficients x (base
    parameters first), without forming the design."""
    b = data.regressor.shape[1]
    out = (data.regressor @ x[:b]).reshape(-1, data.n)
    k = b
    for e, j in effects:
        cols = data.blocks[(e, j)]
        out[:, j] += cols @ x[k : k + cols.shape[1]]
        k += cols.shape[1]
    return out
