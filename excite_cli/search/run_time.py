"""How long an ``optimize`` run takes, measured rather than bounded: real solver iterations of the problem
timed from its first random start, and the solver iterations a run is expected to spend, counted as the
restarts spend them (:mod:`~excite_cli.search.restarts`): the screened starts run ``screen_iterations``
each, the restarts kept run on to ``max_iterations`` (on drafted standing problems they end there or
stall near it), the tasks spread over the workers in rounds, then the kept restart's polish, one round
expected (:data:`EXPECTED_POLISH_ROUNDS`), every round at most. And the sizes a starting config gets so
that the whole sequence fits a budget (:func:`sizes_within`)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from excite_cli.config import OptimizerConfig
from excite_cli.design.excitation import Excitation
from excite_cli.search.optimizer import optimize_restart

#: Solver iterations of the timed run: the time between the first and the last gives one iteration's, the
#: rest a run's own (its start, the projection onto the constraints, the fine check).
TIMED_ITERATIONS = 12
#: Polish rounds the kept restart is expected to run (measured: one, on the drafted Talos, G1 and b1-z1).
EXPECTED_POLISH_ROUNDS = 1
#: The sizes a starting config may get, largest first: (starts screened, restarts, max_iterations).
SIZES = ((16, 4, 400), (8, 2, 400), (8, 2, 300), (6, 2, 250), (4, 2, 200), (0, 2, 150), (0, 1, 100))


@dataclass(frozen=True)
class Timing:
    """Measured times of one problem [s].

    Attributes:
        iteration: one solver iteration (line search and subproblem included).
        run: one run's own time beyond its iterations.
        pieces: one evaluation (value and Jacobian) of the criterion and of each constraint, by name.
    """

    iteration: float
    run: float
    pieces: dict[str, float]


def measure(excitation: Excitation, options: OptimizerConfig, alpha: np.ndarray) -> Timing:
    """The :class:`Timing` of ``excitation`` solved with ``options`` from the start α (n, 2N+1) for
    :data:`TIMED_ITERATIONS`, in this process, and of each piece's evaluation (the median of three)."""
    stamps = []
    start = time.perf_counter()
    optimize_restart(
        excitation.criterion(),
        excitation.constraints,
        options,
        alpha,
        excitation.boundary,
        0,
        lambda *_: stamps.append(time.perf_counter()),
        TIMED_ITERATIONS,
        excitation.fine_basis,
    )
    total = time.perf_counter() - start
    iteration = (stamps[-1] - stamps[0]) / max(len(stamps) - 1, 1) if len(stamps) > 1 else total
    criterion = excitation.criterion()
    pieces = {"criterion": _median(lambda: criterion.value_and_gradient(alpha))}
    pieces |= {c.name: _median(lambda c=c: c.evaluate(alpha)) for c in excitation.constraints}
    return Timing(iteration, max(total - len(stamps) * iteration, 0.0), pieces)


def _median(call) -> float:
    times = []
    for _ in range(3):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def rounds(options: OptimizerConfig, workers: int, polish: int) -> tuple[int, int]:
    """(solver iterations, runs) one sequential iteration spends on its slowest worker: the screened starts
    and the restarts kept, each a task of one worker, in rounds of ``workers``, then ``polish`` rounds."""
    screen = min(options.screen_iterations, options.max_iterations) if options.screened else 0
    screening = math.ceil(options.screened / workers)
    kept = math.ceil(options.restarts / workers)
    iterations = screening * screen + kept * (options.max_iterations - screen) + polish * options.max_iterations
    return iterations, screening + kept + polish


def sequence_seconds(
    options: OptimizerConfig, iterations: int, workers: int, timing: Timing, polish: int | None = None
) -> float:
    """The whole sequence of ``iterations`` [s] (:func:`rounds`), with ``polish`` rounds (default
    :data:`EXPECTED_POLISH_ROUNDS`, at most ``options.polish_rounds``)."""
    polish = min(EXPECTED_POLISH_ROUNDS if polish is None else polish, options.polish_rounds)
    solver, runs = rounds(options, workers, polish)
    return iterations * (solver * timing.iteration + runs * timing.run)


def sizes_within(
    budget: float, options: OptimizerConfig, iterations: int, workers: int, timing: Timing
) -> tuple[dict, float]:
    """The largest of :data:`SIZES` whose expected sequence (:func:`sequence_seconds`, one polish round)
    fits ``budget`` [s], else the smallest: {starts, restarts, max_iterations, polish_rounds} and its
    expected time [s]."""
    for starts, restarts, max_iterations in SIZES:
        sized = {"starts": starts, "restarts": restarts, "max_iterations": max_iterations, "polish_rounds": 1}
        if not starts:
            sized.pop("starts")
        seconds = sequence_seconds(
            options.model_copy(update=sized | {"starts": starts or None}), iterations, workers, timing
        )
        if seconds <= budget:
            break
    return sized, seconds
