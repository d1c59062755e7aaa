"""Recordings of one motion: which configured runs are the same trajectory.

A lab often records each exciting trajectory more than once (each run of a repeated experiment, one
bag per try). Two recordings of one trajectory share its model error, so the folds must hold them
out together and the spread between trajectories must count them as one
(:mod:`~excite_cli.identification.choice.crossval`,
:mod:`~excite_cli.identification.fitting.model_error`): apart, a held-out recording's twin is in the
training data and every effect that fits that trajectory's model error looks like one that
transfers. A run's trajectory is its ``data.runs[].trajectory`` name when it has one; unnamed
recordings are compared by their motion: the deciles of each joint's angle over the recording
(5 %, 10 %, …, 95 %), which do not depend on where in the period the recording starts or how many
periods it holds. Two recordings whose deciles agree within :data:`TOLERANCE` of each joint's range
(at least :data:`STILL`) on every joint are one trajectory; distinct trajectories differ by far more
(780 pairs of random feasible motions of the smoke problem's Panda: 21 % of the range at the least,
33 % the median, on their most different joint and decile).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from excite_cli.identification.data_config import RunConfig

#: The quantiles of each joint's angle a recording's motion is told by.
QUANTILES = np.linspace(0.05, 0.95, 19)
#: Two recordings are one motion when every quantile agrees within this fraction of the joint's range.
TOLERANCE = 0.03
#: [rad] the smallest range a joint's quantiles are compared against (a joint that barely moves).
STILL = 0.05
#: The most samples a recording's quantiles are taken from (evenly spaced: a long run costs no more).
SAMPLES = 20000


def motion_print(q: np.ndarray) -> np.ndarray:
    """(19, n) the quantiles :data:`QUANTILES` of each joint's angle over a recording's q (T, n) [rad]."""
    return np.quantile(q[:: max(1, q.shape[0] // SAMPLES)], QUANTILES, axis=0)


def same_motion(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two recordings' quantiles (:func:`motion_print`, (19, n) each) are one motion."""
    scale = np.maximum(np.maximum(a[-1] - a[0], b[-1] - b[0]), STILL)
    return bool(np.all(np.abs(a - b) <= TOLERANCE * scale))


def trajectory_groups(
    runs: list[RunConfig], folder: Path | None, prints: list[np.ndarray]
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
