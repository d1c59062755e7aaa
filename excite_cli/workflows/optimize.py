"""``optimize``: the sequential generation, its result written after every iteration (resumable), then plots."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

import numpy as np
import yaml

from excite_cli.config import Problem
from excite_cli.config_file import parse_yaml
from excite_cli.design.excitation import Excitation
from excite_cli.design.information import predicted_std
from excite_cli.design.resolve import build_excitation
from excite_cli.errors import ExciteError, FileNotFound, Interrupted, exit_status
from excite_cli.h5 import open_h5
from excite_cli.plots.optimize import figure_paths, plot_result
from excite_cli.search.engine import Engine, default_workers
from excite_cli.search.optimizer import ProgressHook
from excite_cli.search.sequence import IterationResult, run_sequence, stacked_regressors
from excite_cli.storage.paths import check_target, output_lock
from excite_cli.storage.results import read_iterations, write_result
from excite_cli.stored.inputs import read_inputs
from excite_cli.stored.prior import prior_rows

#: The largest cond(C) of a result that identifies something: above it, noise in the torques is
#: amplified a million times into the base parameters (Eq. 5 bounds the relative error by cond(C)).
MAX_USEFUL_COND = 1e6
#: Neighbouring singular values of the stacked C further apart than this leave directions behind the
#: rest (a well-excited C has all within its cond(C), 10–100).
LONE_GAP = 1e3
#: Coefficients the table of improvements shows.
IMPROVED_SHOWN = 8
RESUMABLE_CHANGES = ("sequence.iterations", "optimizer.workers", "optimizer.scheduler", "optimizer.worker_wait")


def engine_for(problem: Problem, excitation: Excitation) -> Engine:
    """Where restarts and draws run: ``optimizer.scheduler``, else ``optimizer.workers`` local
    processes (default: the machine's cores)."""
    cfg = problem.optimizer
    return Engine(excitation, cfg.workers or default_workers(), cfg.scheduler, cfg.worker_wait)


@dataclass
class OptimizeRun:
    """A finished ``optimize``: the problem, its iterations, the result file and the plots."""

    excitation: Excitation
    results: list[IterationResult]
    target: Path
    plots: list[Path]
    prior: np.ndarray | None = None

    @property
    def designed_for(self) -> str:
        """The noise the trajectories were designed for, in words."""
        noise = self.excitation.noise
        return f"designed for {'no declared noise (every row weighs the same)' if noise is None else noise.words}"

    @property
    def improved(self) -> list[tuple[str, float, float]]:
        """With measured prior data (an identify report): the coefficients (base parameters, then
        effects) whose predicted standard deviation the new trajectories cut most, as (name, before,
        after) in their units, most improved first (at most ``IMPROVED_SHOWN``): from the prior's rows
        alone, then stacked with every iteration's, with the report's noise σ̄ per weighted row and its
        rate (each trajectory recorded at the report's rate, :func:`predicted_std`)."""
        measured = self.excitation.measured
        if measured is None or self.prior is None or not self.results:
            return []
        # C holds s·W·Y per recorded row (s the time rule), and the new runs recorded at the same rate
        # carry (their cost-grid rows)/s² of information: std = s·σ̄·√diag((CᵀC)⁻¹)
        noise = measured.noise * measured.time_scale(self.excitation.spec.trajectory.cost_period)
        stacked = stacked_regressors(self.excitation, self.prior, self.results)
        before, after = predicted_std(self.prior, noise), predicted_std(stacked, noise)
        names = [*self.excitation.base.names, *self.excitation.effect_names]
        gain = np.where(np.isinf(before), np.inf, before / after)
        order = np.argsort(-gain, kind="stable")[:IMPROVED_SHOWN]
        return [(names[k], float(before[k]), float(after[k])) for k in order]

    def _lone_direction(self) -> str:
        """Why a cond(C) below :data:`MAX_USEFUL_COND` still hides an unexcited direction, "" when
        nothing: the stacked C's singular values with a gap of more than :data:`LONE_GAP` between two
        neighbours (the directions below it dominate cond(C); a URDF's rounding adds such)."""
        C = np.vstack([*([] if self.prior is None else [self.prior]), *[r.regressor for r in self.results]])
        sigma = np.linalg.svd(C, compute_uv=False)
        ratios = sigma[:-1] / np.maximum(sigma[1:], np.finfo(float).tiny)
        if not ratios.size or ratios.max() <= LONE_GAP:
            return ""
        below = sigma.size - 1 - int(np.argmax(ratios))
        return (
            f"{below} direction(s) of the stacked regressor lie {ratios.max():.3g} times below the rest: cond(C) "
            f"{self.results[-1].cond_stacked:.3g} is theirs, and what they carry no trajectory here excites "
            "(a rounding of the robot's file, or a parameter the limits leave still)"
        )

    @functools.cached_property
    def warning(self) -> str:
        """Why the result should not be run, "" when nothing: an iteration the fine check rejects
        (a constraint no restart could meet, such as ``limits.min_torque_use``), or the stacked
        regressor of the last iteration with cond(C) above :data:`MAX_USEFUL_COND` (rank-deficient
        or nearly: no motion, or limits that leave none), or one with a lone direction
        (:meth:`_lone_direction`)."""
        for result in self.results:
            if result.max_violation > 0:
                return (
                    f"iteration {result.index} violates its constraints on the fine grid (largest normalized "
                    f"violation {result.max_violation:.3g}); no restart met them: do not run it"
                )
        cond = self.results[-1].cond_stacked
        if cond <= MAX_USEFUL_COND:
            return self._lone_direction()
        return (
            f"cond(C) {cond:.3g} after iteration {self.results[-1].index}: the trajectories do not excite every "
            f"base parameter (expected cond(C) ≤ {MAX_USEFUL_COND:g}; are the limits or the frequency leaving "
            "room to move?)"
        )


def run_optimize(
    problem: Problem,
    target: Path,
    force: bool = False,
    resume: bool = False,
    progress: Optional[Callable[[int], ProgressHook]] = None,
    on_iteration: Optional[Callable[[IterationResult], None]] = None,
    engine: Optional[Engine] = None,
) -> OptimizeRun:
    """The sequential generation of ``problem``, writing ``target`` after every iteration, then plots.

    Args:
        force: replace an existing ``target``.
        resume: continue the iterations already in ``target`` (made with the same config, up to
            ``RESUMABLE_CHANGES``); the end result is that of an uninterrupted run.
        progress: see :func:`run_sequence`.
        on_iteration: see :func:`run_sequence`.
        engine: where restarts run (default: :func:`engine_for`).

    Raises:
        ExciteError: bad target, prior data or problem; a result to resume made with another config;
            another run writing ``target`` (:func:`output_lock`); workers lost during the run
            (:class:`~excite_cli.search.engine.Engine`) or no restart of an iteration succeeded
            (:class:`~excite_cli.errors.NoSolution`), with the finished iterations kept in ``target``.
        Interrupted: Ctrl-C or SIGTERM; the finished iterations are in ``target``, the workers stopped.
    """
    check_target(target, "output", force, exists_ok=resume)
    for figure in figure_paths(target):  # written over only where excite wrote them
        check_target(figure, "output", force=True)
    if resume and not target.is_file():
        raise FileNotFound("resume", target, "result to continue")
    stored = read_inputs(problem.effects.model, problem.sequence.prior, problem.folder)  # each opened once
    excitation = build_excitation(problem, stored=stored)
    prior = (
        prior_rows(
            stored.prior, excitation.base, excitation.effect_names, excitation.measured, problem.trajectory.cost_period
        )
        if stored.prior
        else None
    )
    finished = _resumable(target, excitation, prior) if resume else []
    written = list(finished)

    def done(result: IterationResult) -> None:  # ``written`` is what is on disk: a failed write adds nothing
        write_result(target, excitation, [*written, result], problem.optimizer.seed, {"method": "optimized"})
        written.append(result)
        if on_iteration:
            on_iteration(result)

    with output_lock(target, "output"):
        try:
            with engine or engine_for(problem, excitation) as active:
                results = run_sequence(
                    excitation,
                    problem.sequence.iterations,
                    problem.optimizer.seed,
                    prior,
                    progress,
                    done,
                    active,
                    finished,
                )
        except KeyboardInterrupt as exc:
            raise Interrupted(target, len(written), exit_status(exc)) from None
        except ExciteError as exc:  # workers lost, or no restart succeeded: what is finished stays, and says so
            if not written:
                raise
            exc.problem += f"; kept {len(written)} finished iteration(s) in {target}, which a resumed run continues"
            raise exc from None
        return OptimizeRun(excitation, results, target, plot_result(target, excitation, results), prior)


def _resumable(target: Path, excitation: Excitation, prior: Optional[np.ndarray]) -> list[IterationResult]:
    """The iterations of ``target`` if it was made with the same config (see ``RESUMABLE_CHANGES``)."""
    with open_h5(target, "resume") as f:
        stored = parse_yaml(str(f.attrs.get("config", "")), str(target), "resume") or {}
    current = yaml.safe_load(excitation.spec.config.effective)
    if not isinstance(stored, dict):
        raise ExciteError("resume", f"{target} has no valid stored config (not an excite optimize result?)", target)
    for dotted in RESUMABLE_CHANGES:
        section, name = dotted.split(".")
        for config in (stored, current):
            if isinstance(config.get(section), dict):
                config[section].pop(name, None)
    if stored != current:
        differing = sorted(k for k in set(stored) | set(current) if stored.get(k) != current.get(k))
        raise ExciteError(
            "resume", f"{target} was made with another config ({', '.join(differing) or 'the whole file'} differ)"
        )
    finished = read_iterations(target, excitation, prior)
    if len(finished) > excitation.spec.sequence.iterations:
        raise ExciteError(
            "resume",
            f"{target} has {len(finished)} iterations, more than the {excitation.spec.sequence.iterations} asked for",
        )
    return finished
