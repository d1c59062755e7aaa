"""A standing posture searched where the robot's files name none: the legs' joints moved from the zero
posture (legs straight, as a URDF draws a humanoid) until the soles are as they were there, a little
higher (knees slightly bent, as a robot stands: straight knees are a singularity of the legs), with the
centre of mass over the soles' centre."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.optimize import least_squares

from excite_cli.errors import ExciteError

#: The searched posture stands this fraction of the legs' length lower than with straight legs.
KNEE_DROP = 0.03
#: Distance [rad] the searched posture keeps from the leg joints' limits.
LIMIT_MARGIN = 0.05
#: The searched posture's pull towards the zero posture [m/rad] (0.1 rad away weighs as 1 mm of residual),
#: let go of once a posture near it is found.
POSTURE_WEIGHT = 0.01
#: Starts of the posture search, each joint drawn within this of the zero posture [rad] (seed 0).
STARTS, START_SPREAD = 4, 0.2
#: A named posture whose soles are flat within this [m] is taken as it is, else levelled.
LEVEL_TOLERANCE = 5e-4
#: A sole is the collision geometry within this height of its leg's lowest point [m]; its points there
#: at the zero posture are its contact points.
SOLE_HEIGHT = 0.005


def placed_points(model: pin.Model, q: np.ndarray, points: dict[str, tuple[int, np.ndarray]]) -> dict[str, np.ndarray]:
    """{link: (k, 3) its points [m] in the world frame at ``q`` (nq,)}, from ``points`` {link: (joint id,
    (k, 3) points in that joint's frame)}."""
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    return {link: p @ data.oMi[j].rotation.T + data.oMi[j].translation for link, (j, p) in points.items()}


def _leg_joints(model: pin.Model, legs: list[list[int]], q: np.ndarray) -> tuple[list[int], np.ndarray, tuple]:
    """The legs' joint ids, their indices in q, and their bounds :data:`LIMIT_MARGIN` inside the limits (or
    at ``q`` (nq,) where it is closer)."""
    joints = sorted({j for leg in legs for j in leg})
    k = np.array([model.idx_qs[j] for j in joints])
    lower = np.minimum(model.lowerPositionLimit[k] + LIMIT_MARGIN, q[k])
    upper = np.maximum(model.upperPositionLimit[k] - LIMIT_MARGIN, q[k])
    return joints, k, (lower, upper)


def _contact(placed: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """{sole: (k,) which of its points (k, 3) are within :data:`SOLE_HEIGHT` of its lowest}."""
    return {s: p[:, 2] <= p[:, 2].min() + SOLE_HEIGHT for s, p in placed.items()}


def levelled_posture(
    model: pin.Model, points: dict, legs: list[list[int]], soles: list[str], q0: np.ndarray, state: np.ndarray
) -> tuple[np.ndarray, str]:
    """The posture ``state`` (nq,) a robot's files name, its legs' joints moved the least that brings each
    sole's contact points (those within :data:`SOLE_HEIGHT` of its lowest at the zero posture ``q0``) to
    one height as at ``q0`` (flat, where a URDF draws the soles flat), and what changed, in words ("" where
    the soles are within :data:`LEVEL_TOLERANCE` of flat already). Solved by scipy's bounded least squares,
    pulled towards ``state`` by :data:`POSTURE_WEIGHT`.

    Raises:
        ExciteError: (``posture``) the soles cannot be levelled within 1 mm.
    """
    joints, k, (lower, upper) = _leg_joints(model, legs, state)
    points = {s: points[s] for s in soles}
    start = placed_points(model, q0, points)
    contact = _contact(start)
    reference = np.concatenate([start[s][contact[s], 2] for s in soles])

    def conditions(x: np.ndarray) -> np.ndarray:
        q = state.copy()
        q[k] = x
        placed = placed_points(model, q, points)
        rise = np.concatenate([placed[s][contact[s], 2] for s in soles]) - reference
        return rise - rise.mean()

    tilted = float(np.ptp(conditions(state[k])))
    if tilted <= LEVEL_TOLERANCE:
        return state, ""
    solution = least_squares(
        lambda x: np.concatenate([conditions(x), POSTURE_WEIGHT * (x - state[k])]), state[k], bounds=(lower, upper)
    )
    worst = float(np.ptp(conditions(solution.x)))
    if worst > 1e-3:
        raise ExciteError(
            "posture",
            f"the soles of the named posture are tilted by {1000 * tilted:.1f} mm and the legs' joints cannot level "
            f"them (within {1000 * worst:.1f} mm)",
            None,
            "a standing posture with flat soles",
        )
    q = state.copy()
    q[k] = solution.x
    moved = np.abs(solution.x - state[k])
    return q, (
        f"; its soles levelled (they were {1000 * tilted:.1f} mm out of flat): "
        f"{model.names[joints[int(np.argmax(moved))]]} moved most, by {moved.max():.3f} rad"
    )


def searched_posture(
    model: pin.Model, points: dict, legs: list[list[int]], soles: list[str], q0: np.ndarray
) -> tuple[np.ndarray, str]:
    """A standing posture (nq,) from ``q0`` (the legs straight, soles flat), moving the legs' joints
    (module docstring), and what it reached, in words.

    Each sole's contact points (those within :data:`SOLE_HEIGHT` of its lowest at ``q0``) where they were
    at ``q0``, :data:`KNEE_DROP` · L higher (L the legs' length: the base's height above them), the centre
    of mass's ground projection at their centroid, and each sole's centroid where it was relative to the
    first's, solved by scipy's bounded least squares (trust-region reflective) from :data:`STARTS` starts
    near ``q0`` pulled towards it, then without the pull; the joints kept :data:`LIMIT_MARGIN` inside
    their limits.

    Args:
        model: the robot's model (fixed base); points: {link: (joint id, (k, 3) points [m] in its frame)}.
        legs: the legs' joint ids; soles: the sole links; q0: (nq,) the zero posture [rad].

    Raises:
        ExciteError: (``posture``) no such posture within the joints' limits (a residual above 1 mm).
    """
    joints, k, (lower, upper) = _leg_joints(model, legs, q0)
    points = {s: points[s] for s in soles}
    start = placed_points(model, q0, points)
    contact = _contact(start)
    height = min(start[s][:, 2].min() for s in soles)
    drop = KNEE_DROP * abs(height)
    first = start[soles[0]][contact[soles[0]], :2].mean(axis=0)
    apart = {s: start[s][contact[s], :2].mean(axis=0) - first for s in soles}
    data = model.createData()

    def conditions(x: np.ndarray) -> np.ndarray:
        q = q0.copy()
        q[k] = x
        placed = placed_points(model, q, points)
        feet = [placed[s][contact[s]] for s in soles]
        centre = np.vstack(feet)[:, :2].mean(axis=0)
        com = pin.centerOfMass(model, data, q)[:2]
        origin = feet[0][:, :2].mean(axis=0)
        return np.concatenate(
            [np.concatenate([f[:, 2] - start[s][contact[s], 2] - drop for f, s in zip(feet, soles)])]
            + [com - centre]
            + [f[:, :2].mean(axis=0) - origin - apart[s] for f, s in zip(feet, soles)]
        )

    def residuals(x: np.ndarray) -> np.ndarray:
        return np.concatenate([conditions(x), POSTURE_WEIGHT * (x - q0[k])])

    rng = np.random.default_rng(0)  # straight legs are singular (no joint lowers a sole to first order)
    starts = [np.clip(q0[k] + rng.uniform(-START_SPREAD, START_SPREAD, k.size), lower, upper) for _ in range(STARTS)]
    solutions = [least_squares(residuals, x, bounds=(lower, upper), x_scale=0.1) for x in starts]
    solution = min(solutions, key=lambda sol: sol.cost)
    solution = least_squares(conditions, solution.x, bounds=(lower, upper), x_scale=0.1)  # the pull let go
    worst = float(np.abs(conditions(solution.x)).max())
    if worst > 1e-3:
        raise ExciteError(
            "posture",
            f"no standing posture found with the legs' joints {', '.join(model.names[j] for j in joints)}: "
            f"a residual of {1000 * worst:.1f} mm remains (soles flat at one height, the centre of mass over them)",
            None,
            "a standing posture the robot's files name (an SRDF state)",
        )
    q = q0.copy()
    q[k] = solution.x
    return q, (
        f"searched: the soles as at the zero posture {1000 * drop:.0f} mm higher "
        f"({100 * KNEE_DROP:g} % of the legs' length: knees bent), the centre of mass over the soles' centre "
        f"(within {1000 * worst:.2f} mm)"
    )
