"""Sequential generation (Section IV-B): iteration i optimizes with C₀ = [C_prior; C⁽¹⁾; …; C⁽ⁱ⁻¹⁾]."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

import numpy as np

from excite_cli.criterion import condition_number
from excite_cli.errors import ExciteError
from excite_cli.excitation import Excitation
from excite_cli.engine import Engine
from excite_cli.optimizer import ProgressHook, RestartResult, best_restart, optimize_restart
from excite_cli.playback import check_motion, plan_playback


@dataclass(frozen=True)
class IterationResult:
    """One generated trajectory.

    Attributes:
        index: iteration number k, 1-based.
        alpha: (n, 2N+1) Fourier coefficients.
        time: (T_grid,) constraint grid [s]; q, qd, qdd: (T_grid, n) [rad, rad/s, rad/s²] on it.
        regressor: C⁽ᵏ⁾, (T·n_rows, b) base regressor at the cost samples.
        cond_own: cond(C⁽ᵏ⁾); cond_stacked: cond([C₀; C⁽ᵏ⁾]) (Table I).
        excitation_own, excitation_stacked: ē of the same [N·m], the excitation figure that does
            not depend on the choice of base columns (:mod:`excite_cli.information`).
        max_violation: largest normalized constraint violation on the fine grid (≤ 0: satisfied).
        checks: per-constraint figures from the fine grid, units in the names, and those of the
            transitions from and to the home posture (:func:`transition_checks`).
        tracks: per-constraint time series on the constraint grid (``com_xy`` (T_grid, 2) [m],
            ``min_capsule_distance`` (T_grid,) [m]); track_units: their units, from the constraints.
        wall_time_s: optimization wall time [s].
        restarts: every restart of the iteration (:class:`~excite_cli.optimizer.RestartResult`:
            start and end value, solver iterations, first-order optimality, stop reason), in order.
    """

    index: int
    alpha: np.ndarray
    time: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    regressor: np.ndarray
    cond_own: float
    cond_stacked: float
    max_violation: float
    excitation_own: float = 0.0
    excitation_stacked: float = 0.0
    checks: dict[str, float | str] = field(default_factory=dict)
    tracks: dict[str, np.ndarray] = field(default_factory=dict)
    track_units: dict[str, str] = field(default_factory=dict)
    wall_time_s: float = 0.0
    restarts: tuple[RestartResult, ...] = ()

    @property
    def sqp_iterations(self) -> int:
        """Solver iterations of all restarts."""
        return sum(r.iterations for r in self.restarts)

    @property
    def best(self) -> Optional[RestartResult]:
        """The restart whose end point this iteration kept."""
        return best_restart(self.restarts) if self.restarts else None

    @property
    def stop(self) -> str:
        """Why the kept restart ended (:func:`~excite_cli.optimality.stop_reason`), or ``-``."""
        return self.best.stop if self.best else "-"


@dataclass(frozen=True)
class RestartTask:
    """One restart of one iteration (a task for :class:`~excite_cli.engine.Engine`).

    Its random start is drawn from its own seed, ``SeedSequence(seed, spawn_key=(iteration, index))``,
    so the result does not depend on where or in which order the restarts run.

    Attributes:
        iteration: k, 1-based; index: the restart's number, 0-based.
        seed: the run's seed (``optimizer.seed``).
        prior: C₀ (m, b), the rows stacked above the trajectory's regressor (Eq. 41).
        warm_start: (n, 2N+1) accepted α to start from instead of a random start, or None.
    """

    iteration: int
    index: int
    seed: int
    prior: np.ndarray
    warm_start: Optional[np.ndarray] = None

    def rng(self) -> np.random.Generator:
        """The restart's own random generator."""
        return np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(self.iteration, self.index)))

    def __call__(self, excitation: Excitation, progress: Optional[ProgressHook] = None) -> RestartResult:
        """Draw the start (or take the warm start) and optimize from it (:func:`optimize_restart`)."""
        start = self.warm_start.copy() if self.warm_start is not None else excitation.random_start(self.rng())
        return optimize_restart(excitation.criterion(self.prior), excitation.constraints, excitation.problem.optimizer,
                                start, excitation.boundary, self.index, progress)


def describe(excitation: Excitation, index: int, alpha: np.ndarray, prior: np.ndarray, wall_time_s: float = 0.0,
             restarts: Sequence[RestartResult] = ()) -> IterationResult:
    """The :class:`IterationResult` of trajectory α (n, 2N+1) stacked under ``prior`` (m, b): its
    regressor, condition numbers, samples on the constraint grid and every constraint's fine check."""
    own = excitation.criterion().regressor(alpha)
    checks = [c.check(alpha, excitation.fine_basis) for c in excitation.constraints]
    details = {key: value for c in checks for key, value in c.details.items()}
    details.update(transition_checks(excitation, alpha))
    q, qd, qdd = excitation.grid_basis.evaluate(alpha)
    return IterationResult(
        index=index,
        alpha=alpha,
        time=excitation.grid_basis.time,
        q=q,
        qd=qd,
        qdd=qdd,
        regressor=own,
        cond_own=condition_number(own),
        cond_stacked=condition_number(np.vstack([prior, own])),
        excitation_own=excitation.excitation_level(own),
        excitation_stacked=excitation.excitation_level(np.vstack([prior, own])),
        max_violation=max(c.max_violation for c in checks),
        checks=details,
        tracks={key: value for c in excitation.constraints for key, value in c.track(alpha, excitation.grid_basis).items()},
        track_units={key: unit for c in excitation.constraints for key, unit in c.track_units.items()},
        wall_time_s=wall_time_s,
        restarts=tuple(restarts),
    )


def transition_checks(excitation: Excitation, alpha: np.ndarray) -> dict[str, float | str]:
    """Durations [s] of the quintic transitions home → q(0) and q(T) → home (:mod:`excite_cli.playback`)
    and every constraint's largest normalized violation on them, on the fine grid
    (``transition_max_violation`` ≤ 0: satisfied; +inf when no transition keeps the limits)."""
    try:
        playback = plan_playback(excitation, alpha)
    except ExciteError as exc:
        return {"transition_max_violation": np.inf, "transition_worst": str(exc)}
    durations = {s.name: s.duration for s in playback.segments}
    fine_period = excitation.fine_basis.time[1] - excitation.fine_basis.time[0]
    samples = playback.sample(1.0 / fine_period, only=("transition in", "transition out"))
    violation, where = check_motion(excitation.constraints, *samples)
    return {"transition_in_s": durations.get("transition in", 0.0), "transition_out_s": durations.get("transition out", 0.0),
            "transition_max_violation": violation, "transition_worst": where}


def run_sequence(
    excitation: Excitation,
    iterations: int,
    seed: int,
    prior: Optional[np.ndarray] = None,
    progress: Optional[Callable[[int], ProgressHook]] = None,
    on_iteration: Optional[Callable[[IterationResult], None]] = None,
    engine: Optional[Engine] = None,
    finished: Sequence[IterationResult] = (),
) -> list[IterationResult]:
    """Generate ``iterations`` trajectories, each stacking the regressors of the earlier ones (Eq. 41).

    From iteration 2 on, the first restart starts from the previous optimum (repeating earlier data
    keeps cond(C) near cond(C₀), and random starts that satisfy tight balance constraints are far
    from it); the other restarts are random, each from its own seed (:class:`RestartTask`).

    Args:
        excitation: the problem.
        iterations: number K of trajectories.
        seed: seed of the random starts.
        prior: optional C_prior (m, b), e.g. from earlier measured data, stacked first.
        progress: ``progress(k)`` gives the SLSQP progress hook of iteration k.
        on_iteration: called with each finished iteration (e.g. to write it to disk at once).
        engine: where the restarts run (default: serially in this process).
        finished: iterations 1..m already done (a resumed run): the sequence continues with m + 1.
            Each restart's start depends only on (seed, iteration, restart) and the previous
            optimum, so a resumed run ends as an uninterrupted one.

    Returns:
        The K :class:`IterationResult` (the finished ones first).
    """
    if engine is None:
        with Engine(excitation) as serial:
            return run_sequence(excitation, iterations, seed, prior, progress, on_iteration, serial, finished)
    stacked = np.vstack([np.zeros((0, excitation.base.count)) if prior is None else prior, *[r.regressor for r in finished]])
    results: list[IterationResult] = list(finished)
    for k in range(len(finished) + 1, iterations + 1):
        start = time.perf_counter()
        tasks = [RestartTask(k, r, seed, stacked, results[-1].alpha if (r == 0 and results) else None)
                 for r in range(excitation.problem.optimizer.restarts)]
        hook = progress(k) if progress else None
        runs = engine.run(tasks, hook, (lambda r: hook(r.index, r.iterations, r.objective)) if hook else None)
        best = best_restart(runs)
        result = describe(excitation, k, best.alpha, stacked, time.perf_counter() - start, runs)
        stacked = np.vstack([stacked, result.regressor])
        results.append(result)
        if on_iteration:
            on_iteration(result)
    return results
