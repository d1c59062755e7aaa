"""Sequential generation (Section IV-B): iteration i optimizes with C₀ = [C_prior; C⁽¹⁾; …; C⁽ⁱ⁻¹⁾],
continues the best restart the robot can play until it converges (:func:`polish_kept`), starts again
from an earlier iteration's motion (and from the earlier motions' mean) where that is better
(:mod:`~excite_cli.search.earlier_optimum`), keeps the best (:func:`kept_restart`), and describes it."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

import numpy as np

from excite_cli.design.criterion import condition_number
from excite_cli.design.excitation import Excitation
from excite_cli.design.information import PriorInformation
from excite_cli.design.playback import check_motion, plan_playback
from excite_cli.errors import ExciteError, NoSolution
from excite_cli.search.earlier_optimum import from_earlier_optimum
from excite_cli.search.engine import Engine
from excite_cli.search.optimizer import ProgressHook, RestartResult, best_restart
from excite_cli.search.restarts import RestartContext, polish, run_restarts
from excite_cli.trajectory.similarity import correlation


@dataclass(frozen=True)
class IterationResult:
    """One generated trajectory.

    Attributes:
        index: iteration number k, 1-based.
        alpha: (n, 2N+1) Fourier coefficients.
        time: (T_grid,) constraint grid [s]; q, qd, qdd: (T_grid, n) [rad, rad/s, rad/s²] on it.
        regressor: C⁽ᵏ⁾, (T·n_rows, b+e) base regressor (and effect columns) at the cost samples,
            every row as it is: the paper's C, which the figures below are of.
        weighed: (T·n_rows, b+e) the same rows as the design weighs them, each by its noise
            (:attr:`~excite_cli.design.excitation.Excitation.noise`), or None: every row weighs the
            same (then the design's rows are ``regressor``).
        cond_own: cond(C⁽ᵏ⁾); cond_stacked: cond([C₀; C⁽¹⁾; …; C⁽ᵏ⁾]) (Table I), on the base (and effect)
            columns, C₀ the prior rows as the design weighs them (measured data's rows are weighed
            by their noise in weighted least squares) and every iteration's rows as they are.
        scaled_cond_own, scaled_cond_stacked: cond(C L) of the same, the condition number that does
            not depend on the choice of base columns (:mod:`excite_cli.design.information`).
        excitation_own, excitation_stacked: ē of the same [N·m], the excitation figure that does
            not depend on the choice of base columns (:mod:`excite_cli.design.information`).
        max_violation: largest normalized constraint violation on the fine grid (≤ 0: satisfied).
        checks: per-constraint figures from the fine grid, units in the names, and those of the
            transitions from and to the home posture (:func:`transition_checks`).
        tracks: per-constraint time series on the constraint grid (``com_xy`` (T_grid, 2) [m],
            ``min_capsule_distance`` (T_grid,) [m]); track_units: their units, from the constraints.
        wall_time_s: optimization wall time [s].
        restarts: every restart of the iteration (:class:`~excite_cli.search.optimizer.RestartResult`:
            start and end value, solver iterations, first-order optimality, stop reason), in order.
        correlations: ρ of q with each earlier iteration's q on the constraint grid, in order
            (:func:`~excite_cli.trajectory.similarity.correlation`; 1: the same motion again).
        kept: the index of the restart whose end point α is (:func:`kept_restart`); −1: none recorded,
            the best by :func:`~excite_cli.search.optimizer.best_restart`.
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
    kept: int = -1
    weighed: Optional[np.ndarray] = None

    @property
    def design_rows(self) -> np.ndarray:
        """(T·n_rows, b+e) the rows as the design takes them: ``weighed``, or ``regressor`` where every
        row weighs the same; what the next iteration stacks as C₀ (Eq. 41)."""
        return self.regressor if self.weighed is None else self.weighed

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
        if self.kept >= 0:
            return next(r for r in self.restarts if r.index == self.kept)
        return best_restart(self.restarts) if self.restarts else None

    @property
    def stop(self) -> str:
        """Why the kept restart ended (:func:`~excite_cli.search.kkt.stop_reason`), or ``-``."""
        return self.best.stop if self.best else "-"


def stacked_regressors(
    excitation: Excitation, prior: Optional[np.ndarray], results: Sequence[IterationResult]
) -> np.ndarray:
    """C₀ of the next iteration (Eq. 41), as the design weighs it: the prior rows (m, b+e), or none,
    then every earlier iteration's rows (:attr:`IterationResult.design_rows`), in order:
    (m + Σ T·n_rows, b+e)."""
    first = np.zeros((0, excitation.columns)) if prior is None else prior
    return np.vstack([first, *[r.design_rows for r in results]])


def describe(
    excitation: Excitation,
    index: int,
    alpha: np.ndarray,
    prior: Optional[np.ndarray] = None,
    wall_time_s: float = 0.0,
    restarts: Sequence[RestartResult] = (),
    earlier: Sequence[IterationResult] = (),
    kept: int = -1,
) -> IterationResult:
    """The :class:`IterationResult` of trajectory α (n, 2N+1), iteration ``index`` after the ``earlier``
    ones, stacked under the ``prior`` rows (m, b+e; as the design weighs them; None: none) and theirs: its
    regressor (and the rows as the design weighs them), condition numbers, samples on the constraint
    grid, every constraint's fine check, its correlation with each earlier iteration, and the index
    of the restart ``kept``."""
    own = excitation.criterion(weighed=False).regressor(alpha)
    weighed = None if excitation.noise is None else excitation.criterion().regressor(alpha)
    first = np.zeros((0, excitation.columns)) if prior is None else prior
    stacked = np.vstack([first, *[r.regressor for r in earlier], own])
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
        kept=kept,
        weighed=weighed,
    )


def kept_restart(excitation: Excitation, runs: Sequence[RestartResult]) -> RestartResult:
    """The restart an iteration keeps: the lowest objective among those that succeeded whose
    transitions from and to the home posture keep every constraint (:func:`transition_checks`), so
    the robot can play it; the best that succeeded when no transition does (the table says
    ``violated``). The transitions are not optimized: a motion whose q(0) lies across the body from
    home can be excellent and unreachable by the straight joint-space path (seen on the G1: a wrist
    swept through the torso).

    Raises:
        ValueError: no restart succeeded.
    """
    ranked = sorted((r for r in runs if r.succeeded), key=lambda r: (r.objective, r.index))
    if not ranked:
        raise ValueError("no restart succeeded")
    playable = (r for r in ranked if transition_checks(excitation, r.alpha)["transition_max_violation"] <= 0.0)
    return next(playable, ranked[0])


def polish_kept(
    context: RestartContext, runs: list[RestartResult], polished: set[int] | None = None
) -> tuple[list[RestartResult], RestartResult]:
    """``runs`` with the restart the iteration keeps (:func:`kept_restart`) polished
    (:func:`~excite_cli.search.restarts.polish`, in the iteration's ``context``), and that restart. A
    polished end point can lose its playable transitions (seen on the G1: the restart polished to KKT
    9.1e-4 could not be played, and the next one was kept as it was, stalled at 4.4e-2); then the
    restart kept next is polished too, each at most once, so the one kept has always been polished.

    Args:
        polished: indices of the restarts of this iteration polished already (by an earlier call, before
            a restart was added); the ones this call polishes are added to it.
    """
    polished = set() if polished is None else polished
    while (kept := kept_restart(context.excitation, runs)).index not in polished:
        runs = polish(context, runs, kept.index)
        polished.add(kept.index)
    return runs, kept


def transition_checks(excitation: Excitation, alpha: np.ndarray) -> dict[str, float | str]:
    """Durations [s] of the quintic transitions home → q(0) and q(T) → home (:mod:`excite_cli.design.playback`)
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

    Every restart starts from its own random start (:class:`~excite_cli.search.restarts.RestartTask`).
    Where every one ends worse than playing an earlier iteration's motion again, more start from
    that motion and from the earlier motions' mean
    (:func:`~excite_cli.search.earlier_optimum.from_earlier_optimum`), so the stacked criterion never
    ends worse than an earlier optimum's (``sequence.replay``).

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
        hook = progress(k) if progress else None
        context = RestartContext.starting(excitation, engine, k, seed, PriorInformation.of(stacked), hook)
        runs = run_restarts(context)
        if not any(r.succeeded for r in runs):
            failures = sorted({f"{r.stop} ({r.end})" for r in runs})
            raise NoSolution(
                "optimizer",
                f"iteration {k}: none of {len(runs)} restarts reached a result within time_budget "
                f"{excitation.spec.optimizer.time_budget:g} s ({', '.join(failures)})",
                expected="more starts or a longer optimizer.time_budget, or limits that leave the robot room",
            )
        polished: set[int] = set()
        runs, best = polish_kept(context, runs, polished)
        if len(more := from_earlier_optimum(context, runs, best, [r.alpha for r in results])) > len(runs):
            runs, best = polish_kept(context, more, polished)  # not the one polished above again
        result = describe(excitation, k, best.alpha, prior, time.perf_counter() - start, runs, results, best.index)
        results.append(result)
        if on_iteration:
            on_iteration(result)
    return results
