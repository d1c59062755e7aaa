"""The conventional baseline (the paper's ref. [16], Jovic et al., IROS 2015; Table II): many random
Fourier trajectories that satisfy the physical constraints, and a greedy selection of the set.

Each candidate has random Fourier coefficients (amplitudes decaying as 1/k) about the home posture,
scaled per joint to fill its position, velocity and acceleration limits (a fair baseline does not
waste amplitude); if another constraint (CoM region, capsules) then fails on the grid, all joints'
oscillations are shrunk together by bisection to the largest scale that every constraint accepts.
Selection: at iteration i, the candidate that minimizes cond([C⁽¹⁾; …; C⁽ⁱ⁾]) is added.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Optional, Sequence

import numpy as np

from excite_cli.constraints import accepted, farthest_accepted
from excite_cli.constraints.lse import GRID_MARGIN
from excite_cli.design.excitation import Excitation
from excite_cli.search.engine import Engine

#: Bisection steps on the common oscillation scale.
SCALE_STEPS = 10
#: Candidates per draw task (each with its own seed).
DRAWS_PER_TASK = 20


@dataclass(frozen=True)
class Pool:
    """Feasible random candidates.

    Attributes:
        alphas: (K, n, 2N+1) Fourier coefficients.
        regressors: (K, T·rows, b) base regressors at the cost samples.
        generation_time_s: wall time spent drawing and checking them [s].
        drawn: candidates drawn, rejected ones included.
    """

    alphas: np.ndarray
    regressors: np.ndarray
    generation_time_s: float
    drawn: int


def random_candidate(excitation: Excitation, rng: np.random.Generator) -> Optional[np.ndarray]:
    """One feasible random α (n, 2N+1) that uses as much of the limits as the constraints allow, or
    None when even a small motion violates a constraint."""
    alpha = excitation.random_motion(rng, 1.0 - GRID_MARGIN)
    if accepted(excitation.constraints, alpha):
        return alpha
    still = alpha.copy()
    still[:, 1:] = 0.0  # the offsets alone: oscillations scaled by t are still + t (α − still)
    scale = farthest_accepted(excitation.constraints, still, alpha, SCALE_STEPS)
    if scale == 0.0:
        return None
    alpha[:, 1:] *= scale
    return alpha


@dataclass(frozen=True)
class DrawTask:
    """Draw up to ``count`` candidates, or for ``budget_s`` seconds (a task for
    :class:`~excite_cli.search.engine.Engine`), from the seed ``SeedSequence(seed, spawn_key=(index,))``.

    Returns (when called) the kept α (k, n, 2N+1), their regressors (k, T·rows, b) and the draws made.
    """

    index: int
    seed: int
    count: int
    budget_s: Optional[float] = None

    def __call__(
        self, excitation: Excitation, progress: Optional[Callable[[int, int], None]] = None
    ) -> tuple[np.ndarray, np.ndarray, int]:
        rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(self.index,)))
        start = time.perf_counter()
        alphas, drawn = [], 0
        while len(alphas) < self.count and (self.budget_s is None or time.perf_counter() - start < self.budget_s):
            drawn += 1
            alpha = random_candidate(excitation, rng)
            if alpha is not None:
                alphas.append(alpha)
            if progress:
                progress(len(alphas), drawn)
        criterion = excitation.criterion(weighed=False)  # greedy selection by the paper's cond(C)
        shape = (excitation.robot.n_joints, excitation.trajectory.n_coefficients)
        regressors = [criterion.regressor(a) for a in alphas]
        rows = excitation.cost_basis.time.size * excitation.robot.n_rows
        return (
            np.array(alphas).reshape(-1, *shape),
            np.array(regressors).reshape(len(alphas), rows, excitation.columns),
            drawn,
        )


def draw_pool(
    engine: Engine,
    size: Optional[int],
    seed: int,
    budget_s: Optional[float] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Pool:
    """Draw ``size`` feasible candidates, or as many as ``engine``'s workers find in ``budget_s``
    seconds each (``size`` None), in tasks of ``DRAWS_PER_TASK`` candidates with their own seeds:
    the pool does not depend on how many workers draw it.

    Args:
        engine: where the draws run.
        progress: called with (kept, drawn) as draws finish (after every draw when serial).
    """
    start = time.perf_counter()
    if size is None:
        tasks = [DrawTask(k, seed, 10**9, budget_s) for k in range(max(engine.workers, 1))]
    else:
        tasks = [
            DrawTask(k, seed, min(DRAWS_PER_TASK, size - k * DRAWS_PER_TASK)) for k in range(-(-size // DRAWS_PER_TASK))
        ]
    done = {"kept": 0, "drawn": 0}

    def finished(result: tuple[np.ndarray, np.ndarray, int]) -> None:
        done["kept"] += len(result[0])
        done["drawn"] += result[2]
        if progress:
            progress(done["kept"], done["drawn"])

    def serial(kept: int, drawn: int) -> None:
        if progress:
            progress(done["kept"] + kept, done["drawn"] + drawn)

    results = engine.run(tasks, serial, finished)
    alphas = np.concatenate([r[0] for r in results])
    regressors = np.concatenate([r[1] for r in results])
    return Pool(alphas, regressors, time.perf_counter() - start, sum(r[2] for r in results))


def greedy_selection(
    regressors: np.ndarray, count: int, prior: Optional[np.ndarray] = None
) -> tuple[list[int], list[float]]:
    """Greedy set selection: at step i, add the candidate minimizing cond of [prior; selected; it].

    Args:
        regressors: (K, M, b) candidate regressors.
        count: number of steps (each candidate is used at most once).
        prior: optional (m, b) rows stacked first.

    Returns:
        The chosen indices and cond of the stacked regressor after each step. cond is computed from
        the eigenvalues of the Gram matrix CᵀC = Σ C_kᵀ C_k: cond(C) = sqrt(λ_max / λ_min).

    Raises:
        ValueError: fewer candidates than ``count``.
    """
    if len(regressors) < count:
        raise ValueError(f"{len(regressors)} candidates for {count} selections")
    grams = np.einsum("kmi,kmj->kij", regressors, regressors)
    base = np.zeros(grams.shape[1:]) if prior is None else prior.T @ prior
    chosen: list[int] = []
    conds: list[float] = []
    for _ in range(count):
        eig = np.linalg.eigvalsh(base + grams)  # (K, b), ascending
        with np.errstate(divide="ignore", invalid="ignore"):
            cond = np.sqrt(eig[:, -1] / np.where(eig[:, 0] > 0, eig[:, 0], 0.0))
        cond[chosen] = np.inf
        best = int(np.argmin(cond))
        chosen.append(best)
        conds.append(float(cond[best]))
        base = base + grams[best]
    return chosen, conds


def pool_convergence(regressors: np.ndarray, count: int, sizes: Sequence[int]) -> list[tuple[int, list[float]]]:
    """Greedy cond of the stacked regressor per step for the first ``size`` candidates, per size."""
    return [(size, greedy_selection(regressors[:size], count)[1]) for size in sizes if count <= size <= len(regressors)]
