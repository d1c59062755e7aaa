"""What the lab Panda's constraints cost and keep (issue 19): configs/panda_lab.yaml optimized with
and without its torque limits, self-collision and table, each exported at 1 kHz (transitions in
and out, one period) and checked at every sample against the lab config's table, capsules and
effort limits, with pinocchio (forward kinematics, RNEA) and coal, outside the optimizer's code.

Run: `.venv/bin/python bench/panda_lab.py` (about 7 minutes on 2 cores). Prints a table.
"""

from __future__ import annotations

import copy
import tempfile
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from excite_cli.collision.capsules import capsule_pairs, capsules_from_config
from excite_cli.config import ConstraintsConfig
from excite_cli.config_file import load_problem
from excite_cli.dynamics.robot import load_robot
from excite_cli.storage.export import export_trajectory
from excite_cli.workflows.optimize import run_optimize

ROOT = Path(__file__).resolve().parent.parent


def played_checks(problem, result: Path) -> tuple[float, float, float]:
    """Lowest capsule above the table [m], closest checked capsule pair [m] (coal) and largest
    |τ|/effort over every 1 kHz sample of the exported last iteration of ``result``."""
    played = export_trajectory(result, rate=1000.0)
    robot = load_robot(problem, collision=True)
    capsules = capsules_from_config(problem.constraints.self_collision, robot)
    pairs = capsule_pairs(problem.constraints.self_collision, robot, capsules)
    supports = [
        any(robot.model.idx_vs[j] in robot.v_idx for j in robot.model.supports[c.joint] if j > 0) for c in capsules
    ]
    shapes = [coal.Capsule(c.radius, float(np.linalg.norm(c.end - c.start))) for c in capsules]
    data = robot.model.createData()
    lowest, closest, use = np.inf, np.inf, 0.0
    for x in zip(played.q, played.qd, played.qdd):
        state = robot.state(*x)
        pin.forwardKinematics(robot.model, data, state[0])
        ends = [(data.oMi[c.joint].act(c.start), data.oMi[c.joint].act(c.end)) for c in capsules]
        lowest = min([lowest] + [min(a[2], b[2]) - c.radius for (a, b), c, m in zip(ends, capsules, supports) if m])
        placed = []
        for a, b in ends:
            axis = b - a
            rotation = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), axis / np.linalg.norm(axis)).matrix()
            placed.append(coal.Transform3s(rotation, (a + b) / 2))
        for i, j in pairs:
            result_ = coal.DistanceResult()
            coal.distance(shapes[i], placed[i], shapes[j], placed[j], coal.DistanceRequest(), result_)
            closest = min(closest, result_.min_distance)
        tau = pin.rnea(robot.model, data, *state)[robot.v_idx]
        use = max(use, float(np.max(np.abs(tau) / robot.model.effortLimit[robot.v_idx])))
    return lowest, closest, use


def main() -> None:
    lab = load_problem(ROOT / "configs" / "panda_lab.yaml")
    free = copy.deepcopy(lab)
    free.limits.torque, free.constraints = None, ConstraintsConfig()
    print(
        "| run | cond(C) after iterations 1 / 2 / 3 | lowest capsule above the table | closest pair | max abs(τ)/effort |"
    )
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for name, problem in (("lab: torque, self-collision, table", lab), ("joint limits only", free)):
            target = Path(folder) / f"{name.split(':')[0].split()[0]}.h5"
            run = run_optimize(problem, target)
            cond = " / ".join(f"{r.cond_stacked:.1f}" for r in run.results)
            lowest, closest, use = played_checks(lab, target)
            print(f"| {name} | {cond} | {lowest * 100:.2f} cm | {closest * 100:.2f} cm | {use:.2f} |")


if __name__ == "__main__":
    main()
