"""Recordings of one motion: which configured runs are the same trajectory.

A lab often records each exciting trajectory more than once (each run of a repeated experiment, one
bag per try, a first try stopped early). Two recordings of one trajectory share its model error, so
the folds must hold them out together and the spread between trajectories must count them as one
(:mod:`~excite_cli.identification.choice.crossval`,
:mod:`~excite_cli.identification.fitting.model_error`): apart, a held-out recording's twin is in the
training data and every effect that fits that trajectory's model error looks like one that
transfers. A run's trajectory is its ``data.runs[].trajectory`` name when it has one; unnamed
recordings are compared by their path in state space: each recording's joint angles and velocities
(q, q̇) on a :data:`RATE` grid. The shorter of two recordings repeats the longer's motion when at least
:data:`COVERED` of its states lie within :data:`TOLERANCE` of the longer's range (at least
:data:`STILL` rad, :data:`STILL_VELOCITY` rad/s) of a state of the longer's path, on every joint at
once: whatever the start in the period, the number of periods, or where the shorter one stops (a
recording that is the first 60 % of another is its twin). Distinct motions are far apart in this
space (the figures in docs/how-it-works.md).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from excite_cli.identification.data_config import RunConfig

#: [Hz] the grid a recording's states are taken on (velocities by central differences on it).
RATE = 50.0
#: The most states of a recording kept for the comparison (evenly spaced: a long run costs no more).
SAMPLES = 20000
#: A state is on the other recording's path within this fraction of each joint's range.
TOLERANCE = 0.03
#: The fraction of the shorter recording's states that must lie on the longer one's path.
COVERED = 0.95
#: [rad] the smallest range a joint's angle is compared against (a joint that barely moves).
STILL = 0.05
#: [rad/s] the smallest range a joint's velocity is compared against.
STILL_VELOCITY = 0.05
#: The states of the shorter recording tried first: most pairs of distinct motions are told apart by them.
PROBE = 32


class MotionPrint:
    """A recording's path in state space: (m, 2n) states [q, q̇] [rad, rad/s] on the :data:`RATE` grid
    (at most :data:`SAMPLES`), its duration [s] and a k-d tree of the states scaled by their ranges."""

    def __init__(self, time: np.ndarray, q: np.ndarray):
        grid = np.arange(time[0], time[-1], 1.0 / RATE)
        if grid.size < 3:
            grid = np.linspace(time[0], time[-1], 3)
        q = np.column_stack([np.interp(grid, time, q[:, j]) for j in range(q.shape[1])])
        states = np.hstack([q, np.gradient(q, grid, axis=0)])
        self.states = states[:: max(1, states.shape[0] // SAMPLES)]
        self.duration = float(time[-1] - time[0])
        n = q.shape[1]
        floor = np.r_[np.full(n, STILL), np.full(n, STILL_VELOCITY)]
        self.scale = np.maximum(np.ptp(self.states, axis=0), floor)
        self.tree = cKDTree(self.states / self.scale)

    def covered(self, other: "MotionPrint") -> float:
        """The fraction of ``other``'s states within :data:`TOLERANCE` of this path (each dimension
        in this recording's range), from a probe of :data:`PROBE` states when that falls short."""
        probe = other.states[:: max(1, other.states.shape[0] // PROBE)]
        for states in (probe, other.states):
            near = self.tree.query(states / self.scale, p=np.inf, distance_upper_bound=TOLERANCE)[0]
            share = float(np.mean(np.isfinite(near)))
            if share < COVERED:
                break
        return share


def motion_print(time: np.ndarray, q: np.ndarray) -> MotionPrint:
    """The :class:`MotionPrint` of a recording: ``time`` (T,) [s], ``q`` (T, n) [rad]."""
    return MotionPrint(np.asarray(time, dtype=float), np.asarray(q, dtype=float))


def same_motion(a: MotionPrint, b: MotionPrint) -> bool:
    """Whether two recordings are one motion: the shorter's states on the longer's path (module
    docstring)."""
    longer, shorter = (a, b) if a.duration >= b.duration else (b, a)
    return longer.covered(shorter) >= COVERED


def trajectory_groups(
    runs: list[RunConfig], folder: Path | None, prints: list[MotionPrint]
) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """The trajectory of each configured run, and which unnamed recordings repeat another's motion.

    Args:
        runs: ``data.runs`` (files relative to ``folder``).
        prints: (R,) each run's :func:`motion_print`; the runs of one recording (its crops) are
            compared by the first.

    Returns:
        (R,) each run's trajectory as consecutive integers (named runs by name, the others by
        recording, recordings of one motion together), and (run, earlier run) for each unnamed
        recording taken as the same trajectory as an earlier recording.
    """
    keys = [f"name {r.trajectory}" if r.trajectory else f"file {r.recording(folder)}" for r in runs]
    first: dict[str, int] = {}  # each unnamed recording's first run
    for k, r in enumerate(runs):
        if not r.trajectory:
            first.setdefault(keys[k], k)
    repeats, alias = [], {}
    recordings = list(first.items())
    for i, (key, k) in enumerate(recordings):
        earlier = next((m for _, m in recordings[:i] if same_motion(prints[k], prints[m])), None)
        if earlier is not None:
            alias[key] = alias.get(keys[earlier], keys[earlier])
            repeats.append((k, earlier))
    keys = [alias.get(key, key) for key in keys]
    return np.unique(keys, return_inverse=True)[1], repeats
