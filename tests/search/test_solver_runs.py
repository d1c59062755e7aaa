"""How a restart drives its solver: a warm-up, then a fresh quasi-Newton matrix with the criterion's
scale times RESCALE; a run that fails goes on with half the scale, one that stops on its own test
short of stationarity with a finer tolerance."""

from dataclasses import replace

import numpy as np
from conftest import small

from excite_cli.config import NoiseConfig
from excite_cli.constraints import accepted
from excite_cli.design.resolve import build_excitation
from excite_cli.search import optimizer, solver_runs, solvers
from excite_cli.search.kkt import SOLVER_FAILED


def _first_run_cut(panda_problem, monkeypatch, cut=5, warm_up=1000, **ending):
    """A restart whose first solver run is cut after ``cut`` iterations and reported with ``ending`` (its
    other runs as the solver ends them), with a warm-up of ``warm_up`` iterations (default: none within
    the budget): the excitation, the start, each run's (start z, iteration budget, tolerance, scale,
    run) and the restart's result."""
    problem = small(panda_problem)
    problem.noise = NoiseConfig(absolute=0.1)  # every row the same: the paper's criterion
    excitation = build_excitation(problem)
    start = excitation.random_start(np.random.default_rng(5))
    calls = []

    def solve(method, nlp, z0, iterations, tolerance, on_iterate, scale=None):
        run = solvers.solve(method, nlp, z0, cut if not calls else iterations, tolerance, on_iterate, scale)
        calls.append((z0.copy(), iterations, tolerance, scale, run))
        return replace(run, limit=False, **ending) if len(calls) == 1 else run

    monkeypatch.setattr(solver_runs, "solve", solve)
    monkeypatch.setattr(solver_runs, "WARM_UP", warm_up)
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


def test_a_warm_up_then_a_fresh_matrix_with_the_scale_times_rescale(panda_problem, monkeypatch):
    """A-optimality (the plain form) with a warm-up of 20 iterations: the first run has a budget of
    20; where it used them all short of stationarity, the next starts at its last iterate with the
    criterion's scale times RESCALE and the iterations left; they add up in the result."""
    _, _, calls, result = _first_run_cut(panda_problem, monkeypatch, cut=20, warm_up=20)
    (_, warm_budget, _, _, warm), (z, budget, _, scale, rest) = calls[:2]
    assert warm_budget == 20 and warm.iterations == 20 and budget == 60 - 20
    np.testing.assert_array_equal(z, warm.z)
    assert scale == solver_runs.RESCALE * warm.scale
    assert result.iterations == sum(run.iterations for *_, run in calls)


def test_no_warm_up_in_the_epigraph_form(panda_problem, monkeypatch):
    """cond is solved in its epigraph form, whose criterion is its bounds' weights: one run with the
    whole budget, no warm-up."""
    panda_problem.optimizer.objective = "cond"
    _, _, calls, _ = _first_run_cut(panda_problem, monkeypatch, cut=60, warm_up=20)
    assert calls[0][1] == 60


def test_a_failure_after_the_warm_up_goes_on_with_half_the_starts_scale(panda_problem, monkeypatch):
    """The run after the warm-up (its scale up to RESCALE × the start's) is cut after 5 iterations and
    reported failed: the recovery takes half the start's scale, the smaller one, not half the rescaled."""
    problem = small(panda_problem)
    excitation = build_excitation(problem)
    start = excitation.random_start(np.random.default_rng(5))
    calls = []

    def solve(method, nlp, z0, iterations, tolerance, on_iterate, scale=None):
        run = solvers.solve(method, nlp, z0, 5 if len(calls) == 1 else iterations, tolerance, on_iterate, scale)
        calls.append((iterations, scale, run))
        return replace(run, limit=False, failed=True, message="forced") if len(calls) == 2 else run

    monkeypatch.setattr(solver_runs, "solve", solve)
    monkeypatch.setattr(solver_runs, "WARM_UP", 20)
    optimizer.optimize_restart(
        excitation.criterion(), excitation.constraints, problem.optimizer, start, excitation.boundary, max_iterations=60
    )
    (_, _, warm), (_, rescaled, _), (_, recovery, _) = calls[:3]
    assert rescaled > warm.scale  # the warm-up's end still has a large gradient: rescaled upwards
    assert recovery == solver_runs.RECOVERY_SCALE * warm.scale
