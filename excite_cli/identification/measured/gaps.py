"""Gaps in a recording: found, named, and never bridged.

Preprocessing resamples a run to a uniform grid by linear interpolation, then low-passes and
differentiates it. Across a gap (a logger that stalled, messages lost for a second) that would invent
a straight line of positions and torques, whose q̇ and q̈ the filter then spreads over its edges: a
0.5 s gap in a simulated 500 Hz run made the friction estimates about 10 times worse, a 2 s gap gave
the wrong friction model, and nothing was said. So a run is cut at every gap longer than
:data:`GAP_PERIODS` median sample periods and :data:`MIN_GAP_S` (a dropped message, the jitter of a
timestamp or a logger's 9 ms hiccup in a 1 kHz recording is shorter, and interpolation bridges it
well below any cut-off excite uses) into pieces that are resampled, filtered and differentiated
each on its own and stay one run of the fit (one sensor offset, one cross-validation group), each
gap named in a warning; a piece too short to filter (under :data:`MIN_PIECE_S`: the 5 Hz
filter's edges take 1.2 s) is left out, and said so.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from excite_cli.errors import ExciteError, ExciteWarning
from excite_cli.identification.measured.measurements import Run

#: A step between two samples longer than this many median sample periods, and than MIN_GAP_S, is a gap.
GAP_PERIODS = 5.0
#: The shortest gap [s]: over a shorter step, the resampling's linear interpolation of an exciting
#: motion (its band below about 1 Hz) errs by less than 0.3 % of its amplitude, (π f Δt)²/8.
MIN_GAP_S = 0.05
#: Pieces between gaps shorter than this [s] are left out (too short to filter and differentiate).
MIN_PIECE_S = 2.0


@dataclass(frozen=True)
class Gap:
    """A gap in a run: it starts at ``start`` [s] (the last sample before it, on the recording's clock)
    and lasts ``length`` [s]; ``index`` is the sample after it; ``into`` [s] is ``start`` from the run's
    first sample (what the messages say: a bag's clock is the epoch)."""

    start: float
    length: float
    index: int
    into: float = 0.0


def _longest_step(steps: np.ndarray) -> float:
    """The longest step [s] between time stamps that is no gap: :data:`GAP_PERIODS` × the median step,
    at least :data:`MIN_GAP_S`."""
    return max(GAP_PERIODS * float(np.median(steps)), MIN_GAP_S)


def find_gaps(time: np.ndarray) -> list[Gap]:
    """The gaps of a run's time stamps (T,) [s], strictly increasing: steps longer than
    :data:`GAP_PERIODS` × their median and than :data:`MIN_GAP_S`."""
    steps = np.diff(time)
    if steps.size == 0:
        return []
    at = np.flatnonzero(steps > _longest_step(steps))
    return [Gap(float(time[k]), float(steps[k]), int(k + 1), float(time[k] - time[0])) for k in at]


def missing_messages(time: np.ndarray) -> int:
    """Messages missing between the time stamps (T,) [s], outside gaps: each step of k median periods
    (rounded; k ≥ 2, shorter than a gap: :func:`find_gaps`) lacks k − 1 (a sample the resampling bridges)."""
    steps = np.diff(time)
    if steps.size == 0:
        return 0
    period = np.median(steps)
    short = steps[steps <= _longest_step(steps)]
    return int(np.sum(np.maximum(np.rint(short / period) - 1, 0)))


def split_at_gaps(run: Run, quiet: bool = False) -> list[Run]:
    """``run`` cut at its gaps (:func:`find_gaps`) into pieces named ``<name> [t0–t1 s]``, each gap
    and each piece left out (shorter than :data:`MIN_PIECE_S`) named in an
    :class:`~excite_cli.errors.ExciteWarning` (unless ``quiet``: a run read again after it was said);
    ``[run]`` itself when it has none.

    Raises:
        ExciteError: (``data.runs``) the run, or every piece of it, is shorter than :data:`MIN_PIECE_S`:
            nothing of it can be filtered (without interpolating across its gaps, which are named).
    """
    gaps = find_gaps(run.time)
    if not gaps:
        span = float(run.time[-1] - run.time[0]) if run.time.size else 0.0
        if span < MIN_PIECE_S:  # as a piece between gaps would be left out
            raise ExciteError(
                "data.runs",
                f"{run.name} lasts {span:.3g} s, under the {MIN_PIECE_S:g} s a run needs to be filtered and "
                "differentiated",
                run.name,
                "a longer recording (a period of the trajectory or more)",
            )
        return [run]
    bounds = [0] + [g.index for g in gaps] + [run.time.size]
    pieces, short = [], []
    said = "; ".join(f"{g.length:.3f} s at {g.into:.3f} s" for g in gaps)
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        t0, t1 = float(run.time[lo]), float(run.time[hi - 1])
        if t1 - t0 < MIN_PIECE_S:
            short.append(f"{t0 - run.time[0]:.3f}–{t1 - run.time[0]:.3f} s")
            continue
        pick = slice(lo, hi)
        pieces.append(
            replace(
                run,
                name=f"{run.name} [{t0:.3f}–{t1:.3f} s]",
                time=run.time[pick],
                q=run.q[pick],
                qd=None if run.qd is None else run.qd[pick],
                qdd=None if run.qdd is None else run.qdd[pick],
                tau=run.tau[pick],
                dropped=run.dropped if not pieces else 0,
            )
        )
    if not pieces:
        raise ExciteError(
            "data.runs",
            f"{run.name}: {len(gaps)} gap(s) in the recording ({said}) leave no piece of at least "
            f"{MIN_PIECE_S:g} s to filter (pieces {', '.join(short)}); excite never interpolates across a gap",
            run.name,
            "a recording with fewer gaps, or its pieces as runs of their own if they are long enough",
        )
    if quiet:
        return pieces
    left = f"; left out, too short to filter (under {MIN_PIECE_S:g} s): {', '.join(short)}" if short else ""
    warnings.warn(
        f"{run.name}: {len(gaps)} gap(s) in the recording ({said}): cut there into {len(pieces)} piece(s), "
        f"each filtered on its own and never interpolated across{left}",
        ExciteWarning,
        stacklevel=2,
    )
    return pieces
