"""Sequential generation (Section IV-B): iteration i optimizes with C₀ = [C_prior; C⁽¹⁾; …; C⁽ⁱ⁻¹⁾]."""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable, Optional, Sequence

import numpy as np

from excite_cli.errors import ExciteError, NoSolution
from excite_cli.optimization.criterion import condition_number
from excite_cli.optimization.engine import Engine
from excite_cli.optimization.excitation import Excitation
from excite_cli.optimization.optimizer import ProgressHook, RestartResult, best_restart, optimize_restart
from excite_cli.optimization.playback import check_motion, plan_playback
from excite_cli.trajectory.similarity import correlation


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
        correlations: ρ of q with each earlier iteration's q on the constraint grid, in order
            (:func:`~excite_cli.trajectory.similarity.correlation`; 1: the same motion again).
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
    correlations: tuple[float, ...] = ()

    @property
    def max_correlation(self) -> float:
        """The largest ρ with an earlier iteration (NaN for the first): how far from new the motion is."""
        return max(self.correlations) if self.correlations else float("nan")

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
        warm_start: (n, 2N+1) accepted α to start from instead of a random start (a screened start
            that continues), or None.
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
            excitation.fine_basis,
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
    earlier: Sequence[IterationResult] = (),
) -> IterationResult:
    """The :class:`IterationResult` of trajectory α (n, 2N+1) stacked under ``prior`` (m, b): its
    regressor, condition numbers, samples on the constraint grid, every constraint's fine check and
    its correlation with each of the ``earlier`` iterations."""
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
        correlations=tuple(correlation(q, r.q) for r in earlier),
    )


def run_restarts(
    excitation: Excitation,
    engine: Engine,
    k: int,
    seed: int,
    prior: np.ndarray,
    hook: Optional[ProgressHook] = None,
) -> list[RestartResult]:
    """The restarts of iteration k: ``optimizer.restarts`` solver runs of ``max_iterations``, each from
    its own random start.

    With screening (``optimizer.starts`` > ``restarts``), ``starts`` runs of ``screen_iterations``
    first, then the ``restarts`` with the lowest objective among those that succeeded
    (:attr:`RestartResult.succeeded`) continue from their end points for the remaining iterations;
    the others are kept with the stop reason ``screened out``. Which ones continue depends only on
    the screened results, so it does not depend on where they ran.

    When none succeeded, more starts run, as many at a time as the first round, each screened and
    continued the same way, until one succeeds or ``optimizer.time_budget`` seconds have passed since
    the iteration began. Each start's seed depends only on its index, so where it succeeds does not
    depend on the machine (unless the budget ends the search first).

    Returns:
        Every start's :class:`RestartResult`, by index (a continued one with its screening's start
        value, iterations and history included).
    """
    opts = excitation.problem.optimizer
    count = opts.screened or opts.restarts
    deadline = time.perf_counter() + opts.time_budget
    runs = _restart_round(excitation, engine, k, seed, prior, range(count), hook)
    while not any(r.succeeded for r in runs) and time.perf_counter() < deadline:
        runs += _restart_round(excitation, engine, k, seed, prior, range(len(runs), len(runs) + count), hook)
    return runs


def _restart_round(
    excitation: Excitation,
    engine: Engine,
    k: int,
    seed: int,
    prior: np.ndarray,
    indices: range,
    hook: Optional[ProgressHook],
) -> list[RestartResult]:
    """The starts ``indices`` of iteration k, screened and continued as :func:`run_restarts` says."""
    opts = excitation.problem.optimizer
    iterations = min(opts.screen_iterations, opts.max_iterations) if opts.screened else None
    tasks = [RestartTask(k, r, seed, prior, None, iterations) for r in indices]
    runs = engine.run(tasks, hook, (lambda r: hook(r.index, r.iterations, r.objective)) if hook else None)
    if not opts.screened or iterations >= opts.max_iterations:
        return runs
    chosen = sorted((r for r in runs if r.succeeded), key=lambda r: (r.objective, r.index))[: opts.restarts]
    more = [RestartTask(k, r.index, seed, prior, r.alpha, opts.max_iterations - iterations) for r in chosen]
    shift = indices.stop  # continuations count on their own in the progress
    shifted = (lambda r, it, value: hook(shift + r, it, value)) if hook else None
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

    Every restart starts from its own random start (:class:`RestartTask`). None starts from the
    previous optimum: with C₀ holding its rows, the previous optimum is a stationary point of the
    next iteration's criterion too (stacking C on itself scales CᵀC by 2, which moves log det by a
    constant and leaves cond unchanged), so a solver started there stops there and the motion repeats.

    Args:
        excitation: the problem.
        iterations: number K of trajectories.
        seed: seed of the random starts.
        prior: optional C_prior (m, b), e.g. from earlier measured data, stacked first.
        progress: ``progress(k)`` gives the SLSQP progress hook of iteration k.
        on_iteration: called with each finished iteration (e.g. to write it to disk at once).
        engine: where the restarts run (default: serially in this process).
        finished: iterations 1..m already done (a resumed run): the sequence continues with m + 1.
            Each restart's start depends only on (seed, iteration, restart), so a resumed run ends
            as an uninterrupted one.

    Returns:
        The K :class:`IterationResult` (the finished ones first).

    Raises:
        NoSolution: no restart of an iteration succeeded within ``optimizer.time_budget``; the
            iterations before it were passed to ``on_iteration``.
    """
    if engine is None:
        with Engine(excitation) as serial:
            return run_sequence(excitation, iterations, seed, prior, progress, on_iteration, serial, finished)
    results: list[IterationResult] = list(finished)
    for k in range(len(finished) + 1, iterations + 1):
        start, stacked = time.perf_counter(), stacked_regressors(excitation, prior, results)
        runs = run_restarts(excitation, engine, k, seed, stacked, progress(k) if progress else None)
        if not any(r.succeeded for r in runs):
            failures = sorted({f"{r.stop} ({r.end})" for r in runs})
            raise NoSolution(
                "optimizer",
                f"iteration {k}: none of {len(runs)} restarts reached a result within time_budget "
                f"{excitation.problem.optimizer.time_budget:g} s ({', '.join(failures)})",
                expected="more starts or a longer optimizer.time_budget, or limits that leave the robot room",
            )
        best = best_restart(runs)
        result = describe(excitation, k, best.alpha, stacked, time.perf_counter() - start, runs, results)
        results.append(result)
        if on_iteration:
            on_iteration(result)
    return results
