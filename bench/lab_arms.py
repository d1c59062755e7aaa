"""What the lab arms' constraints cost and keep (issue 19): each lab config (default configs/panda.yaml
and configs/ur5.yaml) optimized with and without its torque limits, self-collision and table, each
result exported at 1 kHz (transitions in and out, one period) and checked at every sample against
the lab config's table, capsules and effort limits, with pinocchio (forward kinematics, RNEA) and
coal, outside the optimizer's code.

Run: `.venv/bin/python bench/lab_arms.py [CONFIG ...]` (about 3 minutes on 2 cores for both).
Prints a table.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import copy
import sys
import tempfile
import time
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from excite_cli.collision.capsules import capsule_pairs, capsules_from_config
from excite_cli.config import ConstraintsConfig
from excite_cli.config_file import load_problem
from excite_cli.dynamics.robot import load_robot
from excite_cli.workflows.export import played_result
from excite_cli.workflows.optimize import run_optimize

ROOT = Path(__file__).resolve().parent.parent


def _coal_capsule(a: np.ndarray, b: np.ndarray) -> coal.Transform3s:
    """coal's frame of a capsule from a to b (its axis is z, centred)."""
    axis = (b - a) / max(np.linalg.norm(b - a), 1e-12)
    rotation = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), axis).matrix()
    return coal.Transform3s(rotation, (a + b) / 2)


def played_checks(problem, result: Path) -> tuple[float, float, float]:
    """Lowest moving world capsule above the table [m], closest checked capsule pair [m] (coal) and
    largest |τ|/effort over every 1 kHz sample of the exported last iteration of ``result``."""
    played = played_result(result, rate=1000.0)
    robot = load_robot(problem.robot, problem.folder, collision=True)
    env = problem.constraints.environment
    table = next(s for s in env.shapes if s.type == "half_space")
    point, normal = np.asarray(table.point), np.asarray(table.normal) / np.linalg.norm(table.normal)
    world = capsules_from_config(env, robot, "constraints.environment")
    capsules = capsules_from_config(problem.constraints.self_collision, robot)
    pairs = capsule_pairs(problem.constraints.self_collision, robot, capsules)
    moving = [c for c in world if any(robot.model.idx_vs[j] in robot.v_idx for j in robot.model.supports[c.joint][1:])]
    shapes = [coal.Capsule(c.radius, float(np.linalg.norm(c.end - c.start))) for c in capsules]
    data = robot.model.createData()
    lowest, closest, use = np.inf, np.inf, 0.0
    for x in zip(played.q, played.qd, played.qdd):
        state = robot.state(*x)
        pin.forwardKinematics(robot.model, data, state[0])
        for c in moving:
            ends = (data.oMi[c.joint].act(c.start), data.oMi[c.joint].act(c.end))
            lowest = min(lowest, min(normal @ (e - point) for e in ends) - c.radius)
        placed = [_coal_capsule(data.oMi[c.joint].act(c.start), data.oMi[c.joint].act(c.end)) for c in capsules]
        for i, j in pairs:
            distance = coal.DistanceResult()
            coal.distance(shapes[i], placed[i], shapes[j], placed[j], coal.DistanceRequest(), distance)
            closest = min(closest, distance.min_distance)
        tau = pin.rnea(robot.model, data, *state)[robot.v_idx]
        use = max(use, float(np.max(np.abs(tau) / robot.model.effortLimit[robot.v_idx])))
    return lowest, closest, use


def main(paths: list[Path]) -> None:
    print(
        "| config | run | cond(C) after iterations 1 / 2 / 3 | lowest capsule above the table | closest pair |", end=""
    )
    print(" max abs(τ)/effort | time |")
    print("|---|---|---|---|---|---|---|")
    for path in paths:
        lab = load_problem(path)
        free = copy.deepcopy(lab)
        free.limits.torque, free.constraints = None, ConstraintsConfig()
        with tempfile.TemporaryDirectory() as folder:
            for name, problem in (("torque, self-collision, table", lab), ("joint limits only", free)):
                target = Path(folder) / f"{name.split()[0].strip(',')}.h5"
                start = time.perf_counter()
                run = run_optimize(problem, target)
                seconds = time.perf_counter() - start
                cond = " / ".join(f"{r.cond_stacked:.1f}" for r in run.results)
                lowest, closest, use = played_checks(lab, target)
                print(
                    f"| `{path.name}` | {name} | {cond} | {lowest * 100:.2f} cm | {closest * 100:.2f} cm | {use:.2f} "
                    f"| {seconds // 60:.0f} min {seconds % 60:.0f} s |"
                )


if __name__ == "__main__":
    main([Path(p) for p in sys.argv[1:]] or [ROOT / "configs" / "panda.yaml", ROOT / "configs" / "ur5.yaml"])
