"""Torque channels that carry no signal: a joint whose sensor is off, not connected or drifting near
zero has nothing to fit, and its relative error (of a near-zero RMS torque) would dominate every mean
and the selection's score, while its rows would pull every base parameter towards predicting zero
torque there. Such channels are found by name, their rows get weight 0 in every fit where the other
joints still excite every base parameter, they are left out of the selection score and the mean
errors (:class:`~excite_cli.identification.choice.crossval.CrossValidation` ``scored``, the report's
means), and said in the report's warnings. A simulated Panda whose joint-4 sensor drifts between
−0.0004 and −0.007 Nm identifies at 0.6 % on the other joints (0.57 % with the sensor; 10.4 % with
its rows fitted)."""

from __future__ import annotations

import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.robot import Robot
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.normal import NormalEquations, excited_rank

#: A torque channel whose variation (RMS about its mean) is below this fraction of the URDF model's
#: predicted variation carries no signal: a sensor that is off or drifts near zero. The real and
#: simulated Panda channels are at 0.56-42 times the prediction (docs/how-it-works.md).
WEAK = 0.05


def weak_channels(spread: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """(n,) the joints whose measured torques vary by less than ``WEAK`` times the torques the URDF's
    rigid-body model predicts on the same samples; ``spread``, ``expected``: (n,) their standard
    deviations [Nm] (RMS about the mean, so that a constant sensor offset does not count as signal).
    A joint the model predicts no variation for is never weak."""
    return (expected > 0.0) & (spread < WEAK * expected)


def dead_channels(
    robot: Robot, base: BaseParameters, silent: np.ndarray, datasets: tuple[Dataset, ...]
) -> tuple[np.ndarray, list[str]]:
    """(n,) the joints whose torque channel carries no signal: ``silent`` (mostly exact zeros) or weak
    against the URDF model's torques on ``datasets`` (:func:`weak_channels`), and a line for each."""
    urdf = base.from_standard(robot.urdf_parameters())
    measured = np.vstack([d.tau.reshape(-1, d.n) for d in datasets])
    predicted = np.vstack([(d.regressor @ urdf).reshape(-1, d.n) for d in datasets])
    spread, expected = np.std(measured, axis=0), np.std(predicted, axis=0)
    weak = weak_channels(spread, expected) & ~silent
    lines = [
        f"{robot.joint_names[j]}: the torque channel carries no signal (mostly exact zeros)"
        for j in np.flatnonzero(silent)
    ]
    lines += [
        f"{robot.joint_names[j]}: the torque channel carries no signal (it varies by {spread[j]:.2g} Nm RMS where "
        f"the URDF's model predicts {expected[j]:.2g} Nm: a sensor off or not connected?)"
        for j in np.flatnonzero(weak)
    ]
    tail = "; left out of the fit (unless the other joints miss a base parameter), the selection score and the means"
    return silent | weak, [line + tail for line in lines]


def without_dead_rows(
    normal: NormalEquations, weights: np.ndarray | None, live: np.ndarray | None
) -> np.ndarray | None:
    """(n,) the joints' weights (WLS 1/σ_j, or None for LS) with weight 0 on the dead channels (not
    ``live``), so that their near-zero torques do not pull the fit, unless without their rows the fit
    data no longer excite every base parameter (then ``weights`` unchanged)."""
    if live is None or np.all(live) or not np.any(live):
        return weights
    out = np.ones(normal.n) if weights is None else np.array(weights, dtype=float)
    out[~np.asarray(live, dtype=bool)] = 0.0
    G = normal.system(out, [])[0]
    return out if excited_rank(G) == G.shape[0] else weights
