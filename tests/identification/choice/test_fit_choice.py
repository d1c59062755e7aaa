"""The model and the fit chosen together: every search's start and end under every candidate fit,
J = log CV + p log(1 + min_improvement) recomputed from the table, the lowest wins."""

import numpy as np

from excite_cli.identification.choice.fit_choice import LEAST_SQUARES, candidates, compared_models
from excite_cli.identification.config import IdentificationConfig


def test_candidate_fits_follow_identification_fit():
    cfg = IdentificationConfig(regularization=[1e-3, 1e-2])
    assert candidates(cfg) == [None, 1e-3, 1e-2]
    assert candidates(cfg.model_copy(update={"fit": "least_squares"})) == [None]
    assert candidates(cfg.model_copy(update={"fit": "consistent"})) == [1e-3, 1e-2]


def test_the_pair_with_the_lowest_objective_wins(simulated_identification):
    problem, report, *_ = simulated_identification
    choice, selection = report.fit_choice, report.selection
    models = compared_models(selection)
    assert [m.terms for m in choice.models] == [m.terms for m in models]
    assert len({frozenset(m.terms) for m in models}) == len(models)  # each set of terms once
    price = np.log1p(problem.identification.min_improvement)
    recomputed = np.log(choice.cv) + np.array([[m.effects] for m in models]) * price
    np.testing.assert_allclose(choice.objective, recomputed, rtol=1e-12)
    assert (choice.model, choice.chosen) == np.unravel_index(np.nanargmin(recomputed), recomputed.shape)
    assert choice.names[0] == LEAST_SQUARES and len(choice.names) == 1 + len(problem.identification.regularization)
    # the data hold Coulomb and viscous friction on every joint: the winner has exactly those
    winner = {(t.effect, t.joint) for t in choice.models[choice.model].terms}
    assert winner == {(e, j) for e in ("coulomb", "viscous") for j in range(7)}
