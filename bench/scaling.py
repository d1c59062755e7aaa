"""Wall time of one sequential iteration of the G1 problem against its size.

Starting from configs/g1_arms.yaml (14 arm joints, 10 harmonics, 40 cost samples, all constraints,
2 restarts of 200 SQP iterations, restarts in parallel on the machine's cores), one factor at a time:
active joints 7 (left arm), 14 (both arms), 23 (arms, waist and both hips, base held; hip
and pelvis capsules dropped: they overlap at rest); harmonics 5,
10, 20; cost samples 40, 100 (same 8 s: the cost period shrinks).

SQP iterations are summed over the restarts; "ms per SQP iteration" is the wall time per iteration of
one restart (wall × parallel restarts / iterations), the figure that scales with the problem size.

Run: `.venv/bin/python bench/scaling.py`. Prints a table; asserts nothing.
"""

from __future__ import annotations

import time
from pathlib import Path

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.search.engine import Engine, default_workers
from excite_cli.search.sequence import run_sequence

ROOT = Path(__file__).resolve().parent.parent
ARM = ["shoulder_pitch", "shoulder_roll", "shoulder_yaw", "elbow", "wrist_roll", "wrist_pitch", "wrist_yaw"]
JOINTS = {
    7: [f"left_{j}_joint" for j in ARM],
    14: [f"{side}_{j}_joint" for side in ("left", "right") for j in ARM],
    23: [f"{side}_{j}_joint" for side in ("left", "right") for j in ARM]
    + ["waist_yaw_joint", "waist_roll_joint", "waist_pitch_joint"]
    + [f"{side}_hip_{axis}_joint" for side in ("left", "right") for axis in ("pitch", "roll", "yaw")],
}
CASES = [(7, 10, 40), (14, 10, 40), (23, 10, 40), (14, 5, 40), (14, 20, 40), (14, 10, 100)]


def one_iteration(joints: int, harmonics: int, samples: int) -> tuple[float, float, int, int]:
    problem = load_problem(ROOT / "configs" / "g1_arms.yaml")
    problem.robot.active_joints = JOINTS[joints]
    problem.robot.home_posture = {k: v for k, v in problem.robot.home_posture.items() if k in JOINTS[joints]}
    if joints == 23:  # the hip links sit in the pelvis's capsule and each other's at rest
        problem.constraints.self_collision.ignore_links += [
            "pelvis_contour_link",
            *[f"{side}_hip_{axis}_link" for side in ("left", "right") for axis in ("pitch", "roll", "yaw")],
        ]
    problem.trajectory.harmonics = harmonics
    problem.trajectory.cost_samples = samples
    problem.trajectory.cost_period = 8.0 / samples
    excitation = build_excitation(problem)
    workers = min(default_workers(), problem.optimizer.restarts)
    start = time.perf_counter()
    with Engine(excitation, workers) as engine:
        result = run_sequence(excitation, 1, problem.optimizer.seed, engine=engine)[0]
    return time.perf_counter() - start, result.cond_stacked, excitation.base.count, result.sqp_iterations


def main() -> None:
    print(
        f"{'joints':>6} {'harmonics':>9} {'cost samples':>12} {'base params':>11} {'cond(C)':>8} {'wall [s]':>9} "
        f"{'SQP iterations':>14} {'ms per SQP iteration':>20}"
    )
    for joints, harmonics, samples in CASES:
        wall, cond, count, iterations = one_iteration(joints, harmonics, samples)
        print(
            f"{joints:>6} {harmonics:>9} {samples:>12} {count:>11} {cond:>8.1f} {wall:>9.1f} {iterations:>14} "
            f"{1e3 * wall / max(iterations, 1) * min(default_workers(), 2):>20.0f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
