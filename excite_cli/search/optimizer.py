"""One trajectory optimization (Eq. 7 under the constraints) from one feasible start.

The solver (``optimizer.method``, :mod:`excite_cli.search.solvers`) works on the optimizer's variables z
(boundary conditions met exactly, preconditioned); the criterion and every constraint supply
analytic gradients; a criterion of the extreme singular values (cond, log cond, E-optimality) is
solved in its epigraph form (:class:`~excite_cli.search.nlp.Epigraph`), smooth where the
criterion has a kink at its optimum (a continuation of a restart that stalled in that form runs on
its smoothing, :mod:`~excite_cli.search.smoothing`). Quasi-Newton iterates of this problem approach
the constraint boundary from outside (on the G1 problem SLSQP's iterates stay up to 3 cm outside the
CoM region for most of the run), so a restart ends at the feasible point nearest to the solver's last iterate
(:func:`~excite_cli.search.feasible.project`): what the restart found is then judged by a point
every constraint accepts, with its first-order optimality (:mod:`excite_cli.search.kkt`)
and an honest stop reason.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable, Optional, Sequence

import numpy as np

from excite_cli.config import OptimizerConfig
from excite_cli.constraints import Constraint, accepted
from excite_cli.design.criterion import Criterion
from excite_cli.search.feasible import onto_fine_grid, project, repair
from excite_cli.search.kkt import INFEASIBLE, SOLVER_FAILED, End, Optimality, stop_reason, until_done
from excite_cli.search.nlp import Epigraph, Evaluations, NlpForm
from excite_cli.search.smoothing import Smoothed
from excite_cli.search.solver_runs import solve_warmed
from excite_cli.search.solvers import criterion_scale
from excite_cli.trajectory.boundary import BoundaryConditions
from excite_cli.trajectory.fourier import FourierBasis

#: Progress hook: (restart index, solver iteration, objective at the current iterate).
ProgressHook = Callable[[int, int, float], None]


@dataclass(frozen=True)
class RestartResult:
    """The end of one restart: the best point every constraint accepts, and how the solver got there.

    Attributes:
        index: the restart's number within its iteration, 0-based.
        alpha: (n, 2N+1) Fourier coefficients of the end point.
        objective: criterion value at ``alpha`` (log cond, cond, ...).
        iterations: solver iterations.
        message: the solver's own message.
        wall_time_s: wall time of the restart [s].
        start_objective: criterion value at the start.
        history: (iterations, 2) objective and largest constraint value g (normalized, > 0 outside)
            at each accepted iterate of the solver.
        optimality: first-order optimality at ``alpha`` (:func:`~excite_cli.search.kkt.kkt_optimality`).
        stop: why it ended (:func:`~excite_cli.search.kkt.stop_reason`).
        end: which point was kept: ``projected`` (the feasible point nearest the last iterate),
            ``inside`` (the best iterate inside every constraint), ``bisection`` (towards the start),
            ``start``, ``earlier optimum`` (the start, an earlier iteration's optimum), or ``none``
            (no end point met a constraint that needs motion; ``alpha`` is the start and ``objective`` inf).
        scale: the factor [1] the solver's criterion was multiplied by
            (:attr:`~excite_cli.search.solvers.SolverRun.scale`), which a continuation keeps.
        margins: per constraint, the margin [1] of the problem ``optimality`` belongs to, which a
            continuation keeps (:attr:`~excite_cli.search.nlp.Evaluations.margins`).
    """

    index: int
    alpha: np.ndarray
    objective: float
    iterations: int
    message: str
    wall_time_s: float
    start_objective: float = np.nan
    history: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    optimality: Optimality = Optimality(np.nan, 0, np.nan, np.nan)
    stop: str = ""
    end: str = ""
    scale: Optional[float] = None
    margins: tuple[float, ...] = ()

    @property
    def succeeded(self) -> bool:
        """Whether the solver's run gave a result: it did not fail, and the end point is its own (the
        feasible point nearest its last iterate, or its best iterate inside) or an earlier iteration's
        optimum it started from, not a random start or a bisection towards it."""
        return self.stop not in (SOLVER_FAILED, INFEASIBLE) and self.end in (End.PROJECTED, End.INSIDE, End.EARLIER)


def best_restart(results: Sequence[RestartResult]) -> RestartResult:
    """The restart an iteration keeps: the lowest objective among those that succeeded
    (:attr:`RestartResult.succeeded`), among all when none did (a result written before this rule);
    ties go to the lower index (so the choice does not depend on the order results arrive in)."""
    candidates = [r for r in results if r.succeeded] or list(results)
    return min(candidates, key=lambda r: (r.objective, r.index))


def own_scale(criterion: Criterion, boundary: BoundaryConditions, start: np.ndarray) -> float:
    """The criterion's scale for the solver [1] (:func:`~excite_cli.search.solvers.criterion_scale`)
    from the gradient at ``start`` (n, 2N+1) of the trajectory's own criterion, without C₀.

    With C₀ stacked, the criterion's gradient at a start of little motion is small (the trajectory
    adds little to the prior's information) while its curvature is not (the information grows with
    the square of the motion: the criterion is concave along the motion's amplitude); scaled to that
    gradient, the criterion's curvature came out 100–300 × that of a first iteration, and SLSQP's
    quasi-Newton matrix with it. On the UR10 with a lab's limits, iteration 2 (A-optimality), 11 of
    16 screened starts ended "More than 3*n iterations in LSQ subproblem", most where they began;
    scaled by the trajectory's own gradient, which does not depend on the prior, none did."""
    own = replace(criterion, prior=None) if criterion.prior.rows else criterion
    return criterion_scale(boundary.chain(own.value_and_gradient(start)[1].ravel()))


def optimize_restart(
    criterion: Criterion,
    constraints: Sequence[Constraint],
    options: OptimizerConfig,
    start: np.ndarray,
    boundary: BoundaryConditions,
    index: int = 0,
    progress: Optional[ProgressHook] = None,
    max_iterations: Optional[int] = None,
    fine_basis: Optional[FourierBasis] = None,
    time_limit: Optional[float] = None,
    scale: Optional[float] = None,
    margins: Sequence[float] = (),
    smoothed: bool = False,
) -> RestartResult:
    """Minimize the criterion over α with ``options.method`` from one feasible start.

    The solver stops at its own convergence test, at ``max_iterations``, or, tested at every
    iterate (:func:`~excite_cli.search.kkt.until_done`), at an iterate inside the constraints that meets
    ``options.optimality_tolerance`` (the KKT residual the result is judged by) or once ``time_limit``
    has passed.

    The solver works on the variables z of ``boundary`` (α = s ⊙ (w* + Z z): the boundary conditions
    hold exactly, with diagonal preconditioning s, see :mod:`excite_cli.trajectory.boundary`); everything else
    sees α. The restart ends with the best of: the start, the best iterate whose aggregated
    constraints were all ≤ 0, and the feasible point nearest to the last iterate
    (:func:`~excite_cli.search.feasible.project`; if the projection fails,
    :func:`~excite_cli.search.feasible.repair`); each is confirmed by every constraint's exact grid check.
    The one kept is confirmed on ``fine_basis`` too, the re-check its result is judged by (the grid
    margin covers the overshoot between grid instants, but not always): where that check fails, the
    constraints it rejects get a margin of their own and the point is projected onto that problem,
    or else moved towards the start (:func:`~excite_cli.search.feasible.onto_fine_grid`).

    Args:
        criterion: the criterion (value and gradient).
        constraints: all constraints (values and Jacobians, exact checks, repairs).
        options: method, iterations, tolerances.
        start: (n, 2N+1) α that the boundary conditions and every constraint but those that need
            motion accept.
        boundary: the boundary conditions and the optimizer's coordinates.
        index: the restart's number (passed to ``progress`` and kept in the result).
        progress: called after every solver iteration with the objective at the iterate.
        max_iterations: solver iterations (default ``options.max_iterations``).
        fine_basis: the basis of the fine re-check (default: none).
        time_limit: wall time [s] after which the solver stops (default: none).
        scale: the criterion's scale for the solver, that of the restart this one continues
            (default: set at the start, :func:`~excite_cli.search.solvers.solve`).
        margins: the constraints' margins of the restart this one continues (default: none).
        smoothed: a criterion of the extreme singular values is solved on its smoothing
            (:class:`~excite_cli.search.smoothing.Smoothed`) rather than in its epigraph form: the
            continuation of a restart that stalled in that form.
    """
    begin = time.perf_counter()
    start_value = criterion.value(start)
    problem = Evaluations(criterion, constraints, boundary, start_value, margins)
    history: list[tuple[float, float]] = []

    def on_iterate(z: np.ndarray) -> None:
        history.append((problem.value(z), float(problem.constraint_values(z).max())))
        if progress is not None:
            progress(index, len(history), history[-1][0])

    deadline = begin + (np.inf if time_limit is None else time_limit)
    z0 = boundary.to_variables(start)
    done = until_done(problem, on_iterate, options.optimality_tolerance, deadline)
    # a criterion of the extreme singular values is solved in its epigraph form (smooth where it is not)
    nlp = (Smoothed if smoothed else Epigraph)(problem) if criterion.objective.extremes else problem
    if scale is None and nlp.form is NlpForm.PLAIN:  # the epigraph's criterion is its bounds' weights
        scale = own_scale(criterion, boundary, start)
    limit = max_iterations or options.max_iterations
    run = solve_warmed(options, nlp, z0, limit, lambda w: done(w[: z0.size]), scale)
    run = replace(run, z=run.z[: z0.size])
    out_of_time = time.perf_counter() > deadline
    if len(history) < run.iterations:  # a solver that ends inside an iteration calls back no more: its last iterate
        on_iterate(run.z)
    problem, alpha, end, value = _kept_end(nlp, problem, start, run.z, fine_basis)
    optimality = problem.optimality(alpha)
    history_values = [f for f, _ in history]
    stop = stop_reason(optimality, history_values, run.limit, run.failed, options.optimality_tolerance, out_of_time)
    stop = stop if end is not End.NONE else INFEASIBLE
    return RestartResult(
        index,
        alpha,
        value,
        run.iterations,
        run.message,
        time.perf_counter() - begin,
        start_value,
        np.array(history, dtype=float).reshape(-1, 2),
        optimality,
        stop,
        end,
        run.scale,
        problem.margins,
    )


def _kept_end(
    nlp: Evaluations | Epigraph | Smoothed,
    problem: Evaluations,
    start: np.ndarray,
    last: np.ndarray,
    fine_basis: Optional[FourierBasis],
) -> tuple[Evaluations, np.ndarray, End, float]:
    """The end point a restart keeps (:func:`optimize_restart`): the lowest of its start, the feasible
    point nearest the solver's ``last`` iterate z (n_z,) (or a repair towards the start), and the best
    iterate inside, among those every constraint's grid check accepts; moved onto the fine grid where
    its check fails. Returns the problem it is judged in (with the fine check's margins), its α
    (n, 2N+1), which end it is (``End.NONE`` and the start when none is accepted) and its criterion
    (``inf`` then)."""
    criterion, constraints, boundary = problem.criterion, problem.all, problem.boundary
    ends = [(End.START, start)]
    projected = project(problem, last)
    if projected is not None:
        ends.append((End.PROJECTED, projected))
    else:
        ends.append((End.BISECTION, repair(constraints, boundary.to_alpha(last), start, boundary)))
    if problem.best_inside is not None:
        ends.append((End.INSIDE, problem.best_inside))
    # judged by the criterion the solver minimized: a smoothing's start (a stalled end) can be lower in
    # the criterion itself by what the smoothing costs (excite_cli.search.restarts._smoothed_round weighs that)
    judge = (lambda a: nlp.value(boundary.to_variables(a))) if nlp.form is NlpForm.SMOOTHED else criterion.value
    scored = [
        (judge(alpha), k, name, alpha)
        for k, (name, alpha) in enumerate(ends)
        if name == End.PROJECTED or accepted(constraints, alpha)
    ]  # the projection is already accepted
    if not scored:  # only a constraint that needs motion rejects the start: when no end point meets it, none is kept
        return problem, start, End.NONE, np.inf
    _, _, end, alpha = min(scored, key=lambda item: item[:2])
    if fine_basis is not None and not accepted(constraints, alpha, fine_basis):
        problem, alpha, end = onto_fine_grid(problem, alpha, start, fine_basis)
    return problem, alpha, end, criterion.value(alpha)
