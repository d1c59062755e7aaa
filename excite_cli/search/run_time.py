"""How long an ``optimize`` run takes, measured rather than bounded: real solver iterations of the problem
timed from its first random start, and the solver iterations a run is expected to spend, counted as the
restarts spend them (:mod:`~excite_cli.search.restarts`): the screened starts run ``screen_iterations``
each, the restarts kept run on until they converge, expected after :data:`ITERATIONS_PER_COEFFICIENT`
iterations per Fourier coefficient or at ``max_iterations``, the tasks spread over the workers in rounds;
the kept restart's polish rounds are not expected (where one runs it converges or is dropped early); at
most, every restart to its limit and every polish round to its own. And the sizes a starting config gets
so that the whole sequence fits a budget (:func:`sizes_within`).

The constants are measured on the runs of bench/standing_robots.py (five legged robots drafted by
``init``, 66 and 154 Fourier coefficients, 15 sequential iterations): a solver iteration in a run costs
0.48–0.81 of the first ones' (median 0.59; a run's later iterations search their line less), a kept
restart that converged took 2.4–5.2 iterations per coefficient (median 2.9), and a polish round that ran
added 0–218 iterations of its 300–400.
"""

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
#: A run's solver iteration costs this share of the first ones' timed here (module docstring).
LATER_ITERATIONS = 0.6
#: Solver iterations a restart is expected to converge in, per Fourier coefficient (module docstring).
ITERATIONS_PER_COEFFICIENT = 3
#: The sizes a starting config may get, largest first: (starts screened, restarts, max_iterations).
SIZES = ((16, 4, 400), (8, 2, 400), (8, 2, 300), (6, 2, 250), (4, 2, 200), (0, 2, 150), (0, 1, 100))


@dataclass(frozen=True)
class Timing:
    """Measured times of one problem [s].

    Attributes:
        iteration: one solver iteration of a run (line search and subproblem included): the first ones'
            times :data:`LATER_ITERATIONS`.
        run: one run's own time beyond its iterations.
        pieces: one evaluation (value and Jacobian) of the criterion and of each constraint, by name.
        coefficients: the Fourier coefficients the solver moves.
    """

    iteration: float
    run: float
    pieces: dict[str, float]
    coefficients: int = 0


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
    run = max(total - len(stamps) * iteration, 0.0)
    return Timing(LATER_ITERATIONS * iteration, run, pieces, int(alpha.size))


def _median(call) -> float:
    times = []
    for _ in range(3):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def rounds(options: OptimizerConfig, workers: int, polish: int, length: int | None = None) -> tuple[int, int]:
    """(solver iterations, runs) one sequential iteration spends on its slowest worker: the screened starts
    and the restarts kept, each a task of one worker, in rounds of ``workers``, the kept ones ending after
    ``length`` iterations (default ``max_iterations``), then ``polish`` rounds."""
    screen = min(options.screen_iterations, options.max_iterations) if options.screened else 0
    length = options.max_iterations if length is None else min(max(length, screen), options.max_iterations)
    screening = math.ceil(options.screened / workers)
    kept = math.ceil(options.restarts / workers)
    iterations = screening * screen + kept * (length - screen) + polish * options.max_iterations
    return iterations, screening + kept + polish


def expected_rounds(options: OptimizerConfig, workers: int, timing: Timing) -> tuple[int, int]:
    """:func:`rounds` as a run is expected to spend them: restarts converging after
    :data:`ITERATIONS_PER_COEFFICIENT` per coefficient (or at their limit), no polish round (module
    docstring)."""
    return rounds(options, workers, 0, ITERATIONS_PER_COEFFICIENT * timing.coefficients)


def sequence_seconds(
    options: OptimizerConfig, iterations: int, workers: int, timing: Timing, most: bool = False
) -> float:
    """The whole sequence of ``iterations`` [s]: as expected (:func:`expected_rounds`), or at ``most``
    (every restart to its limit, every polish round)."""
    solver, runs = (
        rounds(options, workers, options.polish_rounds) if most else expected_rounds(options, workers, timing)
    )
    return iterations * (solver * timing.iteration + runs * timing.run)


def sizes_within(
    budget: float, options: OptimizerConfig, iterations: int, workers: int, timing: Timing
) -> tuple[dict, float]:
    """The largest of :data:`SIZES` whose expected sequence (:func:`sequence_seconds`) fits ``budget`` [s],
    else the smallest: {starts, restarts, max_iterations, polish_rounds} and its
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
