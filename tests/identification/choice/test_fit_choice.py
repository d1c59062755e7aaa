"""The model and the fit chosen together: every search's start and end under every candidate fit,
J = log CV + p log(1 + min_improvement) (+ log(1 + least_squares_margin) for least squares)
recomputed from the table, the lowest wins."""

from dataclasses import replace

import numpy as np

from excite_cli.identification.choice.fit_choice import candidates, compared_models
from excite_cli.identification.choice.fit_records import LEAST_SQUARES
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
    recomputed[:, 0] += np.log1p(problem.identification.least_squares_margin)  # least squares' margin
    assert choice.margin == problem.identification.least_squares_margin == 0.5
    np.testing.assert_allclose(choice.objective, recomputed, rtol=1e-12)
    assert (choice.model, choice.chosen) == np.unravel_index(np.nanargmin(recomputed), recomputed.shape)
    assert choice.names[0] == LEAST_SQUARES and len(choice.names) == 1 + len(problem.identification.regularization)
    # the data hold Coulomb and viscous friction on every joint: the winner has exactly those
    winner = {(t.effect, t.joint) for t in choice.models[choice.model].terms}
    assert winner == {(e, j) for e in ("coulomb", "viscous") for j in range(7)}


def test_a_chosen_fit_worse_on_the_validation_data_is_warned_about(simulated_identification):
    """No warning where both fits are at the noise level; with the chosen fit 2 points of RMS torque
    worse on every joint than the other, one line giving both means."""
    _, report, *_ = simulated_identification
    assert report.fit_disagreement() == []
    other = "rms_least_squares" if report.fit_choice.is_consistent else "rms_consistent"
    worse = replace(report, rms_after=report.rms_after + 0.02 * report.rms_torque, **{other: report.rms_after})
    (line,) = worse.fit_disagreement()
    chosen, alternative = worse.mean(worse.relative_after), report.mean(report.relative_after)
    assert chosen > alternative + 1.0
    assert f"({report.fit_choice.name}) predicts the validation data at {chosen:.1f} %" in line
    assert f"at {alternative:.1f} %" in line
