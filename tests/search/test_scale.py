"""The criterion's scale for the solver is that of the trajectory's own criterion: C₀ stacked above it
changes where the optimum is, not what a step of the variables is worth."""

import numpy as np
from conftest import small

from excite_cli.config import NoiseConfig
from excite_cli.design.resolve import build_excitation
from excite_cli.search.optimizer import own_scale
from excite_cli.search.solvers import criterion_scale


def test_the_scale_is_the_trajectorys_own_whatever_the_prior(panda_problem):
    """A prior of another motion's rows, × 0, 1 and 10: the stacked criterion's gradient at the start
    shrinks as the prior grows (the trajectory adds less to it), so a scale set by that gradient grows
    with the prior; the scale is the same for every prior, that of the criterion without one."""
    problem = small(panda_problem)
    problem.noise = NoiseConfig(absolute=0.1)  # every row the same: the paper's criterion
    excitation = build_excitation(problem)
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
