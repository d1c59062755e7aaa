"""A restart's end that the fine re-check rejects (a sample between grid instants beyond a bound):
the constraint the check names gets a margin of its own and the point is projected onto that problem,
whose optimality the restart then reports and any continuation of it keeps."""

import numpy as np
import pytest

from excite_cli.constraints import accepted
from excite_cli.design.resolve import build_excitation
from excite_cli.search.feasible import onto_fine_grid, project
from excite_cli.search.nlp import Evaluations
from excite_cli.search.restarts import RestartTask


@pytest.fixture
def coarse(ur5_problem):
    """The UR5 problem with its constraints sampled every 0.25 s (the fine check every 2.5 ms): a
    point projected onto the grid's constraints overshoots between its instants."""
    ur5_problem.trajectory.constraint_period = 0.25
    return build_excitation(ur5_problem)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_point_the_fine_check_rejects_is_projected_onto_a_problem_with_a_margin_for_it(coarse, seed):
    start = coarse.random_start(np.random.default_rng(seed))
    wide = start.copy()
    wide[:, 1:] *= 3.0  # beyond the limits
    criterion = coarse.criterion()
    problem = Evaluations(criterion, coarse.constraints, coarse.boundary, criterion.value(start))
    on_grid = project(problem, coarse.boundary.to_variables(coarse.boundary.project(wide)))
    assert on_grid is not None and accepted(coarse.constraints, on_grid)
    violations = [c.check(on_grid, coarse.fine_basis).max_violation for c in coarse.constraints]
    assert max(violations) > 0.0  # the case: accepted on the grid, not between its instants

    tightened, alpha, end = onto_fine_grid(problem, on_grid, start, coarse.fine_basis)

    assert end == "projected" and accepted(coarse.constraints, alpha, coarse.fine_basis)
    for margin, violation in zip(tightened.margins, violations):  # a margin where the check failed, only there
        assert margin >= 2.0 * violation if violation > 0.0 else margin == 0.0
    z = coarse.boundary.to_variables(alpha)
    blocks = np.cumsum([0] + [c.values(alpha).size for c in coarse.constraints])
    raised = np.repeat(tightened.margins, np.diff(blocks))
    np.testing.assert_allclose(tightened.constraint_values(z), problem.constraint_values(z) + raised, atol=1e-15)
    assert tightened.constraint_values(z).max() <= 1e-6  # inside the problem it now belongs to


def test_a_continued_restart_keeps_its_margins_and_reports_the_optimality_of_that_problem(coarse):
    margins = tuple(0.02 for _ in coarse.constraints)
    prior = np.zeros((0, coarse.base.count))
    task = RestartTask(1, 0, 3, prior, iterations=15, margins=margins)
    result = task(coarse)
    assert result.margins == margins
    criterion = coarse.criterion(prior)
    tightened = Evaluations(criterion, coarse.constraints, coarse.boundary, result.objective, margins)
    plain = Evaluations(criterion, coarse.constraints, coarse.boundary, result.objective)
    assert result.optimality.residual == pytest.approx(tightened.optimality(result.alpha).residual, rel=1e-9)
    z = coarse.boundary.to_variables(result.alpha)
    assert tightened.constraint_values(z).max() == pytest.approx(plain.constraint_values(z).max() + 0.02)
