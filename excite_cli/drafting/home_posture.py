"""The home posture of a starting config: standing still where every constraint holds (joint,
torque and collision limits), searched from the middle of the joint ranges and from the clearest
of random postures by random steps that increase the smallest clearance to the capsule and world
margins."""

from __future__ import annotations

import numpy as np

from excite_cli.design.excitation import Excitation, violated_at_rest

#: Rounds of random steps, steps per round, clearance sought beyond the margins [m].
HOME_ROUNDS, HOME_STEPS, HOME_CLEARANCE = 60, 64, 0.005


def clearance(excitation: Excitation, Q: np.ndarray) -> np.ndarray:
    """(K,) at each posture Q (K, n) the smallest distance [m] beyond its margin over every capsule
    pair and every capsule and world shape (inf without such constraints)."""
    return np.min([np.full(len(Q), np.inf)] + [c.clearance(Q) for c in excitation.constraints], axis=0)


def home_posture(excitation: Excitation, Q: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, str, bool]:
    """A posture standing still at which every constraint holds (joint, torque and collision limits):
    from the middle of the joint ranges (the most room to move), else from the clearest of the random
    postures Q, random steps that increase the smallest clearance (:func:`clearance`) until it is at
    least ``HOME_CLEARANCE`` and nothing is violated (a torque limit: the steps go on).

    Returns:
        The posture (n,) [rad], how it was found in words, and whether it was: when no such posture
        is found within ``HOME_ROUNDS`` rounds, the best posture found and what binds there (the
        constraint's field and where: a capsule pair, a joint's torque) with the next step, and False.
    """
    centre, half = excitation.limits.centre[0], 0.95 * excitation.limits.half[0]
    scores = clearance(excitation, Q)
    starts = [("the middle of the joint ranges", centre), ("the clearest random posture", Q[np.argmax(scores)])]
    score = -np.inf
    for start, best in starts:
        score, scale = float(clearance(excitation, best[None])[0]), 0.3
        for rounds in range(HOME_ROUNDS):
            if score >= HOME_CLEARANCE and violated_at_rest(excitation, best) is None:
                clear = f"every capsule {score * 100:.1f} cm beyond its margin" if np.isfinite(score) else "no capsule"
                return best, f"from {start}, {rounds} round(s) of random steps: {clear}", True
            steps = best + scale * half * rng.standard_normal((HOME_STEPS, centre.size))
            steps = np.clip(steps, centre - half, centre + half)
            step_scores = clearance(excitation, steps)
            if step_scores.max() > score or score >= HOME_CLEARANCE:
                best, score = steps[np.argmax(step_scores)], float(step_scores.max())
            else:
                scale = max(0.7 * scale, 0.02)
    joints = excitation.robot.joint_names
    violated = violated_at_rest(excitation, best)  # what binds at the best posture found
    binding = (
        f"{violated[0]} fails: {violated[1]}" if violated else f"capsules {score * 100:.2f} cm beyond their margins"
    )
    problem = (
        f"no posture found where every constraint holds at rest in {HOME_ROUNDS} rounds"
        + (f" (best clearance {score * 100:.1f} cm)" if np.isfinite(score) else "")
        + f" with the {len(joints)} active joints {', '.join(joints)}; at the best posture found (written), {binding}"
    )
    return best, problem + "; loosen that constraint's field, or move fewer joints (e.g. one arm's)", False
