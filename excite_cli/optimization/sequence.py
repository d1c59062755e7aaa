"""Sequential generation (Section IV-B): iteration i optimizes with C₀ = [C_prior; C⁽¹⁾; …; C⁽ⁱ⁻¹⁾]."""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable, Optional, Sequence

import numpy as np

from excite_cli.errors import ExciteError
from excite_cli.optimization.criterion import condition_number
from excite_cli.optimization.engine import Engine
from excite_cli.optimization.excitation import Excitation
from excite_cli.optimization.optimizer import ProgressHook, RestartResult, best_restart, optimize_restart
from excite_cli.optimization.playback import check_motion, plan_playback


@dataclass(frozen=True)
class IterationResult:
    """One generated trajectory.

    Attributes:
        index: iteration number k, 1-based.
        alpha: (n, 2N+1) Fourier coefficients.
        time: (T_grid,) constraint grid [s]; q, qd, qdd: (T_grid, n) [rad, rad/s, rad/s²] on it.
        regressor: C⁽ᵏ⁾, (T·n_rows, b) base regressor at the cost samples.
        cond_own: cond(C⁽ᵏ⁾); cond_stacked: cond([C₀; C⁽ᵏ⁾]) (Table I), on the base columns.
        scaled_cond_own, scaled_cond_stacked: cond(C L) of the same, the condition number that does
            not depend on the choice of base columns (:mod:`excite_cli.optimization.information`).
        excitation_own, excitation_stacked: ē of the same [N·m], the excitation figure that does
            not depend on the choice of base columns (:mod:`excite_cli.optimization.information`).
        max_violation: largest normalized constraint violation on the fine grid (≤ 0: satisfied).
        checks: per-constraint figures from the fine grid, units in the names, and those of the
            transitions from and to the home posture (:func:`transition_checks`).
        tracks: per-constraint time series on the constraint grid (``com_xy`` (T_grid, 2) [m],
            ``min_capsule_distance`` (T_grid,) [m]); track_units: their units, from the constraints.
        wall_time_s: optimization wall time [s].
        restarts: every restart of the iteration (:class:`~excite_cli.optimization.optimizer.RestartResult`:
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
    scaled_cond_own: float = np.nan
    scaled_cond_stacked: float = np.nan
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
        """Why the kept restart ended (:func:`~excite_cli.optimization.optimality.stop_reason`), or ``-``."""
        return self.best.stop if self.best else "-"


@dataclass(frozen=True)
class RestartTask:
    """One restart of one iteration (a task for :class:`~excite_cli.optimization.engine.Engine`).

    Its random start is drawn from its own seed, ``SeedSequence(seed, spawn_key=(iteration, index))``,
    so the result does not depend on where or in which order the restarts run.

    Attributes:
        iteration: k, 1-based; index: the restart's number, 0-based.
        seed: the run's seed (``optimizer.seed``).
        prior: C₀ (m, b), the rows stacked above the trajectory's regressor (Eq. 41).
        warm_start: (n, 2N+1) accepted α to start from instead of a random start, or None.
        iterations: solver iterations (default ``optimizer.max_iterations``).
    """

    iteration: int
    index: int
    seed: int
    prior: np.ndarray
    warm_start: Optional[np.ndarray] = None
    iterations: Optional[int] = None

    def rng(self) -> np.random.Generator:
        """The restart's own random generator."""
        return np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(self.iteration, self.index)))

    def __call__(self, excitation: Excitation, progress: Optional[ProgressHook] = None) -> RestartResult:
        """Draw the start (or take the warm start) and optimize from it (:func:`optimize_restart`)."""
        start = self.warm_start.copy() if self.warm_start is not None else excitation.random_start(self.rng())
        return optimize_restart(
            excitation.criterion(self.prior),
            excitation.constraints,
            excitation.problem.optimizer,
            start,
            excitation.boundary,
            self.index,
            progress,
            self.iterations,
        )


def stacked_regressors(
    excitation: Excitation, prior: Optional[np.ndarray], results: Sequence[IterationResult]
) -> np.ndarray:
    """C₀ of the next iteration (Eq. 41): the prior rows (m, b), or none, then every earlier
    iteration's regressor, in order: (m + Σ T·n_rows, b)."""
    first = np.zeros((0, excitation.base.count)) if prior is None else prior
    return np.vstack([first, *[r.regressor for r in results]])


def describe(
    excitation: Excitation,
    index: int,
    alpha: np.ndarray,
    prior: np.ndarray,
    wall_time_s: float = 0.0,
    restarts: Sequence[RestartResult] = (),
) -> IterationResult:
    """The :class:`IterationResult` of trajectory α (n, 2N+1) stacked under ``prior`` (m, b): its
    regressor, condition numbers, samples on the constraint grid and every constraint's fine check."""
    own = excitation.criterion().regressor(alpha)
    stacked = np.vstack([prior, own])
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
        cond_stacked=condition_number(stacked),
        scaled_cond_own=excitation.scaled_condition_number(own),
        scaled_cond_stacked=excitation.scaled_condition_number(stacked),
        excitation_own=excitation.excitation_level(own),
        excitation_stacked=excitation.excitation_level(stacked),
        max_violation=max(c.max_violation for c in checks),
        checks=details,
        tracks={
            key: value for c in excitation.constraints for key, value in c.track(alpha, excitation.grid_basis).items()
        },
        track_units={key: unit for c in excitation.constraints for key, unit in c.track_units.items()},
        wall_time_s=wall_time_s,
        restarts=tuple(restarts),
    )


def run_restarts(
    excitation: Excitation,
    engine: Engine,
    k: int,
    seed: int,
    prior: np.ndarray,
    warm_start: Optional[np.ndarray],
    hook: Optional[ProgressHook] = None,
) -> list[RestartResult]:
    """The restarts of iteration k: ``optimizer.restarts`` solver runs of ``max_iterations``, the
    first from ``warm_start`` (n, 2N+1) when given, the others from random starts.

    With screening (``optimizer.starts`` > ``restarts``), ``starts`` runs of ``screen_iterations``
    first, then the ``restarts`` with the lowest objective continue from their end points for the
    remaining iterations; the others are kept with the stop reason ``screened out``. Which ones
    continue depends only on the screened results, so it does not depend on where they ran.

    Returns:
        Every start's :class:`RestartResult`, by index (a continued one with its screening's start
        value, iterations and history included).
    """
    opts = excitation.problem.optimizer
    count, iterations = (
        (opts.screened, min(opts.screen_iterations, opts.max_iterations)) if opts.screened else (opts.restarts, None)
    )
    tasks = [RestartTask(k, r, seed, prior, warm_start if r == 0 else None, iterations) for r in range(count)]
    runs = engine.run(tasks, hook, (lambda r: hook(r.index, r.iterations, r.objective)) if hook else None)
    if not opts.screened or iterations >= opts.max_iterations:
        return runs
    chosen = sorted(runs, key=lambda r: (r.objective, r.index))[: opts.restarts]
    more = [RestartTask(k, r.index, seed, prior, r.alpha, opts.max_iterations - iterations) for r in chosen]
    shifted = (lambda r, it, value: hook(count + r, it, value)) if hook else None  # continuations count on their own
    continued = {
        c.index: c
        for c in engine.run(more, shifted, (lambda c: shifted(c.index, c.iterations, c.objective)) if hook else None)
    }
    screened = {r.index: r for r in chosen}
    return [
        _joined(screened[r.index], continued[r.index]) if r.index in continued else replace(r, stop="screened out")
        for r in runs
    ]


def _joined(screen: RestartResult, more: RestartResult) -> RestartResult:
    """One restart of a screening and its continuation."""
    return replace(
        more,
        iterations=screen.iterations + more.iterations,
        start_objective=screen.start_objective,
        wall_time_s=screen.wall_time_s + more.wall_time_s,
        history=np.vstack([screen.history, more.history]),
    )


def transition_checks(excitation: Excitation, alpha: np.ndarray) -> dict[str, float | str]:
    """Durations [s] of the quintic transitions home → q(0) and q(T) → home (:mod:`excite_cli.optimization.playback`)
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
    return {
        "transition_in_s": durations.get("transition in", 0.0),
        "transition_out_s": durations.get("transition out", 0.0),
        "transition_max_violation": violation,
        "transition_worst": where,
    }


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
    results: list[IterationResult] = list(finished)
    for k in range(len(finished) + 1, iterations + 1):
        start, stacked = time.perf_counter(), stacked_regressors(excitation, prior, results)
        runs = run_restarts(
            excitation,
            engine,
            k,
            seed,
            stacked,
            results[-1].alpha if results else None,
            progress(k) if progress else None,
        )
        result = describe(excitation, k, best_restart(runs).alpha, stacked, time.perf_counter() - start, runs)
        results.append(result)
        if on_iteration:
            on_iteration(result)
    return results
