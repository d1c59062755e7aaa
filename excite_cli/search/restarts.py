"""The restarts of one iteration (Sec. IV-A): tasks of one solver run each, from a random start of
their own, screened and continued, and more of them when every one failed."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Optional

import numpy as np

from excite_cli.design.excitation import Excitation
from excite_cli.design.information import PriorInformation
from excite_cli.search.engine import Engine
from excite_cli.search.kkt import CONVERGED, SCREENED_OUT, STALLED, TIME_BUDGET
from excite_cli.search.optimizer import ProgressHook, RestartResult, optimize_restart
from excite_cli.search.smoothing import log_criterion, smoothing_bound


@dataclass(frozen=True)
class RestartTask:
    """One restart of one iteration (a task for :class:`~excite_cli.search.engine.Engine`).

    Its random start is drawn from its own seed, ``SeedSequence(seed, spawn_key=(iteration, index))``,
    so the result does not depend on where or in which order the restarts run.

    Attributes:
        iteration: k, 1-based; index: the restart's number, 0-based.
        seed: the run's seed (``optimizer.seed``).
        prior: what the criterion needs of C₀, the rows stacked above the trajectory's regressor
            (Eq. 41): b+e-square blocks, however many rows C₀ has.
        warm_start: (n, 2N+1) accepted α to start from instead of a random start (a screened start
            that continues), or None.
        iterations: solver iterations (default ``optimizer.max_iterations``).
        time_limit: wall time [s] after which its solver stops (default: none).
        scale: the criterion's scale of the run it continues (:attr:`RestartResult.scale`), or None
            for a start of its own; margins: the constraints' margins of the run it continues
            (:attr:`RestartResult.margins`).
        smoothed: a criterion of the extreme singular values is solved on its smoothing (the
            continuation of a restart that stalled in its epigraph form, :func:`polish`).
    """

    iteration: int
    index: int
    seed: int
    prior: PriorInformation
    warm_start: Optional[np.ndarray] = None
    iterations: Optional[int] = None
    time_limit: Optional[float] = None
    scale: Optional[float] = None
    margins: tuple[float, ...] = ()
    smoothed: bool = False

    def rng(self) -> np.random.Generator:
        """The restart's own random generator."""
        return np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(self.iteration, self.index)))

    def __call__(self, excitation: Excitation, progress: Optional[ProgressHook] = None) -> RestartResult:
        """Draw the start (or take the warm start) and optimize from it (:func:`optimize_restart`)."""
        start = self.warm_start.copy() if self.warm_start is not None else excitation.random_start(self.rng())
        return optimize_restart(
            excitation.criterion(self.prior),
            excitation.constraints,
            excitation.spec.optimizer,
            start,
            excitation.boundary,
            self.index,
            progress,
            self.iterations,
            excitation.fine_basis,
            self.time_limit,
            self.scale,
            self.margins,
            self.smoothed,
        )


@dataclass(frozen=True)
class RestartContext:
    """What the restarts of one iteration share.

    Attributes:
        excitation: the design; engine: where the restarts run.
        k: the iteration, 1-based; seed: the run's seed (``optimizer.seed``).
        prior: what the criterion needs of C₀ (:class:`RestartTask`).
        deadline: the iteration's time budget ends here [s, ``time.perf_counter``].
        hook: progress (restart index, solver iteration, objective), or None.
    """

    excitation: Excitation
    engine: Engine
    k: int
    seed: int
    prior: PriorInformation
    deadline: float
    hook: Optional[ProgressHook] = None

    @classmethod
    def starting(
        cls, excitation: Excitation, engine: Engine, k: int, seed: int, prior: PriorInformation, hook=None
    ) -> "RestartContext":
        """The context of iteration k beginning now: its deadline ``optimizer.time_budget`` seconds away."""
        return cls(
            excitation, engine, k, seed, prior, time.perf_counter() + excitation.spec.optimizer.time_budget, hook
        )

    def task(self, index: int, start=None, iterations=None, scale=None, margins=(), smoothed=False) -> RestartTask:
        """Restart ``index`` of the iteration (:class:`RestartTask`), its time limit what is left."""
        left = _left(self.deadline)
        return RestartTask(self.k, index, self.seed, self.prior, start, iterations, left, scale, margins, smoothed)

    def run(self, tasks: list[RestartTask], hook: Optional[ProgressHook]) -> list[RestartResult]:
        """``tasks`` on the engine, ``hook`` told of each solver iteration and of each result."""
        return self.engine.run(tasks, hook, (lambda r: hook(r.index, r.iterations, r.objective)) if hook else None)


def run_restarts(context: RestartContext) -> list[RestartResult]:
    """The restarts of the context's iteration: ``optimizer.restarts`` solver runs of
    ``max_iterations``, each from its own random start.

    With screening (``optimizer.starts`` > ``restarts``), ``starts`` runs of ``screen_iterations``
    first, then the ``restarts`` with the lowest objective among those that succeeded
    (:attr:`RestartResult.succeeded`) continue from their end points for the remaining iterations;
    the others are kept with the stop reason ``screened out``. Which ones continue depends only on
    the screened results, so it does not depend on where they ran.

    Every solver run stops at the context's deadline (its time limit is what remains of the budget
    when its round begins).

    When none succeeded, more starts run, as many at a time as the first round, each screened and
    continued the same way, until one succeeds or the deadline has passed. Each start's seed depends
    only on its index, so where it succeeds does not depend on the machine (unless the budget ends the
    search first).

    Returns:
        Every start's :class:`RestartResult`, by index (a continued one with its screening's start
        value, iterations and history included).
    """
    opts = context.excitation.spec.optimizer
    count = opts.screened or opts.restarts
    runs = _restart_round(context, range(count))
    while not any(r.succeeded for r in runs) and _left(context.deadline) > 0.0:
        runs += _restart_round(context, range(len(runs), len(runs) + count))
    return runs


def polish(context: RestartContext, runs: list[RestartResult], kept: int) -> list[RestartResult]:
    """``runs`` with the restart of index ``kept`` continued from its end point until it converges:
    at most ``optimizer.polish_rounds`` solver runs of ``max_iterations`` each, every one from a fresh
    quasi-Newton matrix, while time is left before the context's deadline.

    A BFGS matrix built along a long path can stop describing the curvature where the path ends:
    SLSQP then takes steps too short to move the objective and stops "stalled" or at its limit short
    of the KKT tolerance. Started again from the same point with the identity (Nocedal & Wright,
    Numerical Optimization, 2nd ed., Sec. 6.1, on restarting quasi-Newton methods), it converges:
    on the Panda (iteration 2, seed 0) a restart stalled at KKT 5.1e-2 converged in 70 more
    iterations, to a lower value. A continuation that fails or ends higher is not kept. A criterion of
    the extreme singular values still stalled after the rounds runs one more, on its smoothing
    (:func:`_smoothed_round`).

    Args:
        context: the iteration's (its hook told of the polished restart's iterations counted on from
            where it stopped).
        runs: every restart of the iteration (:func:`run_restarts`); kept: the index of the one to polish.

    Returns:
        ``runs`` with the polished restart in its place, its iterations and history joined; its stop
        is ``time budget`` when the deadline came before it converged.
    """
    opts, runs, hook = context.excitation.spec.optimizer, list(runs), context.hook
    at = next(i for i, r in enumerate(runs) if r.index == kept)
    for _ in range(opts.polish_rounds):
        current = runs[at]
        if current.stop == CONVERGED or _left(context.deadline) <= 0.0:
            break
        task = context.task(kept, current.alpha, opts.max_iterations, current.scale, current.margins)
        shifted = (lambda r, it, value: hook(r, current.iterations + it, value)) if hook else None
        more = context.run([task], shifted)[0]
        if not more.succeeded or more.objective > current.objective:
            break
        runs[at] = _joined(current, more)
    if opts.polish_rounds and runs[at].stop == STALLED and _left(context.deadline) > 0.0:
        runs[at] = _smoothed_round(context, runs[at])
    if opts.polish_rounds and runs[at].stop != CONVERGED and _left(context.deadline) <= 0.0:
        runs[at] = replace(runs[at], stop=TIME_BUDGET)  # not polished to the end: the budget decided
    return runs


def _smoothed_round(context: RestartContext, current: RestartResult) -> RestartResult:
    """``current``, a kept restart of a criterion of the extreme singular values that stalled in its
    epigraph form, continued on the criterion's smoothing for ``max_iterations``
    (:mod:`~excite_cli.search.smoothing`); the continuation is kept when it is lower, or when it
    converged (Clarke's test of the criterion itself) higher by no more than the smoothing can cost
    (:func:`~excite_cli.search.smoothing.smoothing_bound` at ``current``). Any other criterion:
    ``current``."""
    criterion = context.excitation.criterion(context.prior)
    if not criterion.objective.extremes:
        return current
    opts, hook = context.excitation.spec.optimizer, context.hook
    task = context.task(current.index, current.alpha, opts.max_iterations, current.scale, current.margins, True)
    shifted = (lambda r, it, value: hook(r, current.iterations + it, value)) if hook else None
    more = context.run([task], shifted)[0]
    rise = log_criterion(criterion, more.alpha) - log_criterion(criterion, current.alpha)
    bound = smoothing_bound(criterion, current.alpha)
    if more.succeeded and (rise <= 0.0 or (more.stop == CONVERGED and rise <= bound)):
        return replace(
            _joined(current, more), message=f"stalled in epigraph form, then on its smoothing: {more.message}"
        )
    return current


def _restart_round(context: RestartContext, indices: range) -> list[RestartResult]:
    """The starts ``indices`` of the context's iteration, screened and continued as :func:`run_restarts` says."""
    opts, hook = context.excitation.spec.optimizer, context.hook
    iterations = min(opts.screen_iterations, opts.max_iterations) if opts.screened else None
    runs = context.run([context.task(r, iterations=iterations) for r in indices], hook)
    if not opts.screened or iterations >= opts.max_iterations:
        return runs
    chosen = sorted((r for r in runs if r.succeeded), key=lambda r: (r.objective, r.index))[: opts.restarts]
    if not chosen:  # every screened start failed: nothing to continue
        return runs
    more = [context.task(r.index, r.alpha, opts.max_iterations - iterations, r.scale, r.margins) for r in chosen]
    shift = indices.stop  # continuations count on their own in the progress
    shifted = (lambda r, it, value: hook(shift + r, it, value)) if hook else None
    continued = {c.index: c for c in context.run(more, shifted)}
    screened = {r.index: r for r in chosen}
    return [
        _joined(screened[r.index], continued[r.index]) if r.index in continued else replace(r, stop=SCREENED_OUT)
        for r in runs
    ]


def _left(deadline: float) -> float:
    """Seconds left until ``deadline`` (``time.perf_counter``), at least 0."""
    return max(0.0, deadline - time.perf_counter())


def _joined(screen: RestartResult, more: RestartResult) -> RestartResult:
    """One restart of a screening and its continuation."""
    return replace(
        more,
        iterations=screen.iterations + more.iterations,
        start_objective=screen.start_objective,
        wall_time_s=screen.wall_time_s + more.wall_time_s,
        history=np.vstack([screen.history, more.history]),
    )
