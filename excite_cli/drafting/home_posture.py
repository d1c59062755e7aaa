"""The home posture of a starting config: standing still where every constraint holds (joint,
torque and collision limits, the zero-moment point of a standing robot), searched from the posture
the robot's files stand in (a standing robot's), the middle of the joint ranges and the clearest of
random postures by random steps that increase the smallest slack: each distance constraint's
clearance beyond its margin less what a home keeps beyond it (``Constraint.home_clearance``: 5 mm from
capsules, 2 cm for the zero-moment point)."""

from __future__ import annotations

import numpy as np

from excite_cli.design.excitation import Excitation, violated_at_rest

#: Rounds of random steps, steps per round.
HOME_ROUNDS, HOME_STEPS = 60, 64


def slack(excitation: Excitation, Q: np.ndarray) -> np.ndarray:
    """(K,) at each posture Q (K, n) the smallest clearance [m] beyond its margin, less the constraint's
    ``home_clearance``, over every constraint that keeps a distance (inf without such constraints)."""
    return np.min(
        [np.full(len(Q), np.inf)] + [c.clearance(Q) - c.home_clearance for c in excitation.constraints], axis=0
    )


def _clearances(excitation: Excitation, q: np.ndarray) -> str:
    """Each distance constraint's clearance at the posture q (n,), in words ("" without any)."""
    found = [(c.name, float(c.clearance(q[None])[0])) for c in excitation.constraints]
    return ", ".join(f"{name} {100 * d:.1f} cm" for name, d in found if np.isfinite(d))


def home_posture(
    excitation: Excitation, Q: np.ndarray, rng: np.random.Generator, first: np.ndarray | None = None
) -> tuple[np.ndarray, str, bool]:
    """A posture standing still at which every constraint holds (joint, torque and collision limits, the
    zero-moment point) with each distance constraint's ``home_clearance`` to spare: from ``first`` (the
    posture the robot's files stand in) when given, else from the middle of the joint ranges (the most room
    to move), else from the clearest of the random postures Q (K, n), random steps that increase the smallest
    slack (:func:`slack`) until it is ≥ 0 and nothing is violated (a torque limit: the steps go on).

    Returns:
        The posture (n,) [rad], how it was found in words, and whether it was: when no such posture
        is found within ``HOME_ROUNDS`` rounds from each start, the best posture found and what binds
        there (the constraint's field and where: a capsule pair, a joint's torque) with the next step,
        and False.
    """
    centre, half = excitation.limits.centre[0], 0.95 * excitation.limits.half[0]
    starts = [
        ("the middle of the joint ranges", centre),
        ("the clearest random posture", Q[np.argmax(slack(excitation, Q))]),
    ]
    if first is not None:
        starts.insert(0, ("the posture the robot's files stand in", np.clip(first, centre - half, centre + half)))
    score = -np.inf
    for start, best in starts:
        score, scale = float(slack(excitation, best[None])[0]), 0.3
        for rounds in range(HOME_ROUNDS):
            if score >= 0 and violated_at_rest(excitation, best) is None:
                clear = _clearances(excitation, best)
                return (
                    best,
                    f"from {start}, {rounds} round(s) of random steps: "
                    + (f"beyond the margins, {clear}" if clear else "no capsule"),
                    True,
                )
            steps = best + scale * half * rng.standard_normal((HOME_STEPS, centre.size))
            steps = np.clip(steps, centre - half, centre + half)
            step_scores = slack(excitation, steps)
            if step_scores.max() > score or score >= 0:
                best, score = steps[np.argmax(step_scores)], float(step_scores.max())
            else:
                scale = max(0.7 * scale, 0.02)
    joints = excitation.robot.joint_names
    violated = violated_at_rest(excitation, best)  # what binds at the best posture found
    clear = _clearances(excitation, best)
    binding = f"{violated[0]} fails: {violated[1]}" if violated else f"beyond the margins, {clear}"
    problem = (
        f"no posture found where every constraint holds at rest in {HOME_ROUNDS} rounds"
        + (f" (clearances beyond the margins {clear})" if clear else "")
        + f" with the {len(joints)} active joints {', '.join(joints)}; at the best posture found (written), {binding}"
    )
    return best, problem + "; loosen that constraint's field, or move fewer joints (e.g. one arm's)", False
