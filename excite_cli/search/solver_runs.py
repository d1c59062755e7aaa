"""How a restart drives its solver: a warm-up, then the run with a fresh quasi-Newton matrix, and
runs again after a failure or a stop short of stationarity.

SLSQP starts its quasi-Newton matrix of the Lagrangian at the identity in the scaled variables
(:func:`~excite_cli.search.solvers.solve`), and keeps every curvature pair it has seen. Its first
iterations, far from any optimum and before the constraints that bind are known, leave pairs that
no longer describe the problem where the solver ends; and the scale that sets the first step
(:func:`~excite_cli.search.solvers.criterion_scale`, from the start's gradient) is that of a point
far from the optimum. So an SLSQP restart of the plain form (A- and D-optimality) runs ``WARM_UP``
iterations, then starts the solver again from where it got, with a fresh matrix and the criterion's
scale times ``RESCALE``, at most the scale whose first step there is a start's (``FIRST_STEP``): on
the UR10 with a lab's limits, where the gradient had not fallen after the warm-up, × 3 drove capsules
through each other and failed a start, as a longer first step from a start does. Its quasi-Newton
matrix grows from the curvature near the optimum instead of carrying the warm-up's: the same idea as
restarting a quasi-Newton method after its initial phase (Nocedal & Wright, *Numerical
Optimization*, 2006, Sec. 6.1, on the initial matrix's scale). On the G1 arms (``make optimize``,
the default) the kept restarts took 700 / 698 / 533 SLSQP iterations, against 1144 / 945 / 976
without, to the same criterion (3.413 / 3.032 / 2.826 against 3.416 / 3.033 / 2.826); the figures
page gives the other robots and seeds.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable, Optional

import numpy as np

from excite_cli.config import OptimizerConfig
from excite_cli.search.kkt import stationary
from excite_cli.search.nlp import Epigraph, Evaluations, NlpForm
from excite_cli.search.smoothing import Smoothed
from excite_cli.search.solvers import SolverRun, criterion_scale, solve

#: Runs of the solver after one that failed or stopped on its own test short of stationarity
#: (:func:`solve_recovering`); the factor on the criterion's scale after a failure, and on the
#: solver's tolerance after its own test.
RECOVERIES, RECOVERY_SCALE, RECOVERY_TOLERANCE = 2, 0.5, 1e-3
#: Solver iterations before the plain form's solver starts again (module docstring), and the factor on
#: the criterion's scale it starts again with.
WARM_UP, RESCALE = 20, 3.0


def solve_warmed(
    options: OptimizerConfig,
    nlp: Evaluations | Epigraph | Smoothed,
    z0: np.ndarray,
    iterations: int,
    on_iterate: Callable[[np.ndarray], None],
    scale: Optional[float],
) -> SolverRun:
    """:func:`solve_recovering` from z0 (n_z,) for at most ``iterations``; SLSQP in the plain form: a warm-up
    of ``WARM_UP`` iterations first, then, unless it ended stationary (``options.optimality_tolerance``)
    or short of its limit, the rest of the iterations from its end with a fresh quasi-Newton matrix and
    the criterion's scale times ``RESCALE``, or less: no more than
    :func:`~excite_cli.search.solvers.criterion_scale` at the warm-up's end, so that the fresh matrix's
    first step is no longer than a start's (module docstring). The runs' iterations add up; the
    result's scale is the last run's."""
    if options.method != "SLSQP" or nlp.form is not NlpForm.PLAIN or iterations <= WARM_UP:
        return solve_recovering(options, nlp, z0, iterations, on_iterate, scale)
    warm = solve_recovering(options, nlp, z0, WARM_UP, on_iterate, scale)
    if warm.iterations < WARM_UP or stationary(nlp.problem, warm.z[: z0.size], options.optimality_tolerance):
        return warm
    scale = min(warm.scale * RESCALE, criterion_scale(nlp.gradient(warm.z)))  # a first step no longer than a start's
    rest = solve_recovering(options, nlp, warm.z, iterations - warm.iterations, on_iterate, scale, warm.scale)
    return replace(rest, iterations=rest.iterations + warm.iterations)


def solve_recovering(
    options: OptimizerConfig,
    nlp: Evaluations | Epigraph | Smoothed,
    z0: np.ndarray,
    iterations: int,
    on_iterate: Callable[[np.ndarray], None],
    scale: Optional[float],
    start_scale: Optional[float] = None,
) -> SolverRun:
    """:func:`~excite_cli.search.solvers.solve`, run again (up to ``RECOVERIES`` times, a fresh
    quasi-Newton matrix each, for the iterations left; they add up) where it ended neither at its
    limit nor at the KKT test of :func:`~excite_cli.search.kkt.until_done`:

    - it failed on its own (SLSQP's "More than 3*n iterations in LSQ subproblem" or "Positive
      directional derivative for linesearch", IPOPT's restoration): from the best iterate inside
      every constraint so far (the start if none), the criterion's scale times ``RECOVERY_SCALE``. A
      first step that drove two capsules through each other (their segments crossing) left SLSQP's
      linearized constraints inconsistent; with half the scale the same UR10 start (a lab's limits)
      reached the best criterion of its 16 screened starts. After a warm-up (``start_scale``, the
      scale the restart started with, below the rescaled one) the scale is halved from the smaller
      of the two: on the UR10 with a lab's limits two screened starts failed after the warm-up and,
      from half the rescaled scale (about the start's), failed again and ended at their start; from
      half the start's they ended inside at 0.68 and 0.69 from 3.5 and 3.1;
    - its own convergence test passed (SLSQP: the criterion changed by less than its tolerance) at a
      point whose KKT residual is above ``optimality_tolerance``: from its last iterate, its tolerance
      times ``RECOVERY_TOLERANCE``. With C₀ stacked the criterion's gradient is small beside the
      trajectory's own, which sets the scale (:func:`~excite_cli.search.optimizer.own_scale`), so the
      first step of a later iteration can change the criterion by less than the tolerance: on the G1
      (seed 1, iteration 3) a restart ended after 1 iteration at its start, 3.047 against the other
      restart's 2.835."""

    variables, problem = nlp.start, nlp.problem  # the epigraph's bounds start at their extremes

    tolerance = options.tolerance
    run = solve(options.method, nlp, variables(z0), iterations, tolerance, on_iterate, scale)
    done = run.iterations
    for _ in range(RECOVERIES):
        short = run.failed or not stationary(problem, run.z[: z0.size], options.optimality_tolerance)
        if run.limit or done >= iterations or not short:
            break
        if run.failed:
            inside = problem.best_inside
            w = variables(z0 if inside is None else problem.boundary.to_variables(inside))
            scale = min(run.scale, start_scale or run.scale) * RECOVERY_SCALE
        else:
            w, scale, tolerance = run.z, run.scale, tolerance * RECOVERY_TOLERANCE
        run = solve(options.method, nlp, w, iterations - done, tolerance, on_iterate, scale)
        done += run.iterations
    return replace(run, iterations=done)
