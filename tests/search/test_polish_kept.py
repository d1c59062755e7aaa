"""The restart an iteration keeps has always been polished, also when the polished end point of the
best one can no longer be played (its transitions from and to home break a limit)."""

from dataclasses import replace

import numpy as np

from excite_cli.search import sequence
from excite_cli.search.kkt import CONVERGED, STALLED
from excite_cli.search.optimizer import RestartResult


def test_the_restart_kept_is_one_that_was_polished(monkeypatch):
    """Restart 0 is the best and is polished first; its polished end point cannot be played, so
    restart 1 is kept: it is polished too, once, and restart 2 is not."""
    runs = [
        RestartResult(i, np.full((1, 3), float(i)), value, 200, "", 1.0, stop=STALLED, end="projected")
        for i, value in ((0, 1.0), (1, 2.0), (2, 3.0))
    ]
    polished = []

    def polish(context, runs, kept):
        polished.append(kept)
        done = {"objective": runs[kept].objective - 0.5, "alpha": np.full((1, 3), 10.0 + kept), "stop": CONVERGED}
        return [replace(r, **done) if r.index == kept else r for r in runs]

    def transition_checks(excitation, alpha):  # restart 0's polished end point breaks a limit on its way home
        return {"transition_max_violation": 1.0 if alpha[0, 0] == 10.0 else -1.0}

    monkeypatch.setattr(sequence, "polish", polish)
    monkeypatch.setattr(sequence, "transition_checks", transition_checks)
    out, kept = sequence.polish_kept(sequence.RestartContext(None, None, 1, 0, np.zeros((0, 2)), 0.0), runs)
    assert polished == [0, 1]
    assert kept is sequence.kept_restart(None, out)
    assert kept.index == 1 and kept.stop == CONVERGED and kept.objective == 1.5


def test_a_restart_polished_before_one_was_added_is_not_polished_again(monkeypatch):
    """After the kept restart 0 was polished, a restart is added (from an earlier iteration's motion)
    whose transitions cannot be played: restart 0 is kept again, as it was, without a second polish."""
    runs = [RestartResult(0, np.zeros((1, 3)), 1.0, 200, "", 1.0, stop=STALLED, end="projected")]
    polished = []

    def polish(context, runs, kept):
        polished.append(kept)
        return runs

    def transition_checks(excitation, alpha):  # the added restart (alpha 7) breaks a limit on its way home
        return {"transition_max_violation": 1.0 if alpha[0, 0] == 7.0 else -1.0}

    monkeypatch.setattr(sequence, "polish", polish)
    monkeypatch.setattr(sequence, "transition_checks", transition_checks)
    context, done = sequence.RestartContext(None, None, 1, 0, np.zeros((0, 2)), 0.0), set()
    runs, kept = sequence.polish_kept(context, runs, done)
    added = [*runs, RestartResult(1, np.full((1, 3), 7.0), 0.5, 50, "", 1.0, stop=CONVERGED, end="earlier optimum")]
    _, kept = sequence.polish_kept(context, added, done)
    assert polished == [0] and kept.index == 0 and done == {0}
