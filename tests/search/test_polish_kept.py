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
