"""The sequence never loses ground (Sec. IV-B): an iteration whose restarts all end worse than
playing an earlier iteration's motion again runs more restarts, from that motion and from the mean
of the earlier motions.

Stacked on C₀, the motion of an earlier iteration is a point the problem allows (it met every
constraint on the fine grid, and its transitions were checked) and often a good one: on the G1 with
the paper's criterion every restart of iteration 2 ended above the cond(C) that playing iteration 1
again keeps (11.38 and 13.13 against 11.23; stacking C on itself doubles CᵀC and leaves cond unchanged). A solver
started there may stop there (for iteration 2 that point is stationary again), and the motion then
repeats: the correlation with the earlier iteration says so (1: the same motion).

Once two or more motions are stacked, playing one of them again no longer keeps cond: C₀ᵀC₀ is
the sum of their information, and what keeps cond is a motion whose information is that sum's
mean (stacking a multiple of C₀ᵀC₀ leaves cond unchanged). The motion of the mean Fourier
coefficients α has that information up to the square of the motions' spread (CᵀC is smooth in α), so
where the earlier motions are near one another (the sequence of a criterion whose optimum every
iteration finds again) it is the start that keeps cond; where they are far apart it is one more start.
``sequence.replay: false`` asks for a new motion every iteration instead, even where the stacked
criterion rises.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np

from excite_cli.search.kkt import End
from excite_cli.search.optimizer import RestartResult
from excite_cli.search.restarts import RestartContext


def from_earlier_optimum(
    context: RestartContext, runs: list[RestartResult], kept: RestartResult, earlier: Sequence[np.ndarray]
) -> list[RestartResult]:
    """``runs`` and, where an ``earlier`` iteration's α (n, 2N+1) scores lower in this iteration's
    criterion (C₀ of the ``context`` stacked above it) than the ``kept`` restart's end point, one more
    restart of ``max_iterations`` from the lowest of them and, with two or more earlier iterations, one
    from their mean α (both on the context's engine at once), their indices the next free ones. When
    the restart from the earlier motion ends where it started, its end is ``End.EARLIER`` (a result, not
    a random start: see :attr:`~excite_cli.search.optimizer.RestartResult.succeeded`), so the iteration
    can keep it.

    Returns:
        ``runs`` unchanged (the kept restart is at least as good as every earlier optimum, or there is
        none, or ``sequence.replay`` is false), or ``runs`` with the new restarts last.
    """
    if not earlier or not context.excitation.spec.sequence.replay:
        return runs
    criterion = context.excitation.criterion(context.prior)
    values = [criterion.value(alpha) for alpha in earlier]
    best = int(np.argmin(values))
    if not values[best] < kept.objective:
        return runs
    index = max(r.index for r in runs) + 1
    starts = [earlier[best].copy()] + ([np.mean(earlier, axis=0)] if len(earlier) > 1 else [])
    results = context.run([context.task(index + i, start) for i, start in enumerate(starts)], context.hook)
    replayed = replace(results[0], end=End.EARLIER) if results[0].end == End.START else results[0]
    return [*runs, replayed, *results[1:]]
