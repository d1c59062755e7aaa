"""The criterion's scale for the solver is that of the trajectory's own criterion: C₀ stacked above it
changes where the optimum is, not what a step of the variables is worth; a solver run that fails
goes on with half of it."""

from dataclasses import replace

import numpy as np
from conftest import small

from excite_cli.constraints import accepted
from excite_cli.design.resolve import build_excitation
from excite_cli.search import optimizer, solvers
from excite_cli.search.kkt import SOLVER_FAILED
from excite_cli.search.optimizer import own_scale
from excite_cli.search.solvers import criterion_scale


def test_the_scale_is_the_trajectorys_own_whatever_the_prior(panda_problem):
    """A prior of another motion's rows, × 0, 1 and 10: the stacked criterion's gradient at the start
    shrinks as the prior grows (the trajectory adds less to it), so a scale set by that gradient grows
    with the prior; the scale is the same for every prior, that of the criterion without one."""
    excitation = build_excitation(small(panda_problem))
    rng = np.random.default_rng(3)
    start, other = excitation.random_start(rng), excitation.random_start(rng)
    rows = excitation.criterion().regressor(other)

    def gradient(criterion):
        return excitation.boundary.chain(criterion.value_and_gradient(start)[1].ravel())

    alone = criterion_scale(gradient(excitation.criterion()))
    stacked = [excitation.criterion(weight * rows) for weight in (1.0, 10.0)]
    assert criterion_scale(gradient(stacked[1])) > 10.0 * alone  # what the scale was set by before
    for criterion in [excitation.criterion(), *stacked]:
        assert own_scale(criterion, excitation.boundary, start) == alone


def _first_run_cut(panda_problem, monkeypatch, **ending):
    """A restart whose first solver run is cut after 5 iterations and reported with ``ending`` (its
    other runs as the solver ends them): the excitation, the start, each run's (start z, iteration
    budget, tolerance, scale, run) and the restart's result."""
    problem = small(panda_problem)
    excitation = build_excitation(problem)
    start = excitation.random_start(np.random.default_rng(5))
    calls = []

    def solve(method, nlp, z0, iterations, tolerance, on_iterate, scale=None):
        run = solvers.solve(method, nlp, z0, 5 if not calls else iterations, tolerance, on_iterate, scale)
        calls.append((z0.copy(), iterations, tolerance, scale, run))
        return replace(run, limit=False, **ending) if len(calls) == 1 else run

    monkeypatch.setattr(optimizer, "solve", solve)
    result = optimizer.optimize_restart(
        excitation.criterion(), excitation.constraints, problem.optimizer, start, excitation.boundary, max_iterations=60
    )
    return excitation, start, calls, result


def test_a_solver_that_fails_goes_on_from_its_best_point_inside_with_half_the_scale(panda_problem, monkeypatch):
    """The first solver run is cut after 5 iterations and reported failed (as SLSQP's "More than 3*n
    iterations in LSQ subproblem" is): the restart runs the solver again, from a point every
    constraint accepts that is better than the start (its best iterate inside), with the criterion's
    scale halved, for the iterations left; its iterations add up, and it does not end failed."""
    excitation, start, calls, result = _first_run_cut(panda_problem, monkeypatch, failed=True, message="forced")
    assert len(calls) == 2
    (_, first_budget, _, _, first), (z, budget, _, scale, second) = calls
    assert first.iterations == 5 and budget == first_budget - 5 == 55
    assert scale == 0.5 * first.scale
    point, criterion = excitation.boundary.to_alpha(z), excitation.criterion()
    assert accepted(excitation.constraints, point) and criterion.value(point) < criterion.value(start)
    assert result.iterations == 5 + second.iterations and result.stop != SOLVER_FAILED


def test_a_solver_that_stops_on_its_own_test_short_of_stationarity_goes_on_with_a_finer_tolerance(
    panda_problem, monkeypatch
):
    """The first solver run is cut after 5 iterations and reported as ended by its own test (as
    SLSQP's "Optimization terminated successfully" when a later iteration's first step changes the
    criterion by less than its tolerance), far from a KKT point: the solver runs again from its last
    iterate with the same scale and a tolerance 1000 times finer, for the iterations left."""
    _, _, calls, result = _first_run_cut(panda_problem, monkeypatch, message="own test")
    assert len(calls) == 2
    (_, _, first_tolerance, _, first), (z, _, tolerance, scale, second) = calls
    np.testing.assert_array_equal(z, first.z)
    assert scale == first.scale and tolerance == 1e-3 * first_tolerance
    assert result.iterations == 5 + second.iterations
