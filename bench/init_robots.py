"""`excite init` on five arms of example-robot-data that no shipped config uses, each config used without
an edit: the dry run (`excite check`), `excite optimize --iterations 1`, `excite export` at 100 Hz, and
the exported samples checked independently of excite's constraints: every joint inside the URDF's
position, velocity and effort limits (pinocchio's model and RNEA of the full URDF), and every moving
link's collision geometry above the mounting plane (coal, the meshes themselves, not excite's
capsules; links the config says the plane ignores are reported apart). the figures of the documentation under
"Starting on one's own robot".

    .venv/bin/python bench/init_robots.py
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import coal
import h5py
import numpy as np
import pinocchio as pin

from excite_cli.config_file import load_problem
from excite_cli.dynamics.robot_files import example_robot_data_root, open_source

ROBOTS = {
    "UR10": "ur_description/urdf/ur10_robot.urdf",
    "UR3": "ur_description/urdf/ur3_robot.urdf",
    "xArm 7": "xarm_description/urdf/xarm7.urdf",
    "Unitree Z1": "z1_description/urdf/z1.urdf",
    "SO-ARM100": "so_arm_description/urdf/so100.urdf",
    "Kinova Jaco 2": "kinova_description/robots/kinova.urdf",
}
EXCITE = [sys.executable, "-m", "excite_cli"]


def _run(args: list[str], cwd: Path) -> tuple[float, int, str]:
    """Time [s], exit status and the last line of ``excite args``; a status other than 0 or 1 (a
    warning: the result is written) stops the bench."""
    start = time.perf_counter()
    done = subprocess.run(EXCITE + args, cwd=cwd, capture_output=True, text=True)
    if done.returncode not in (0, 1):
        raise SystemExit(f"excite {' '.join(args)} failed:\n{done.stdout}\n{done.stderr}")
    lines = (done.stderr.strip() or done.stdout.strip()).splitlines()
    return time.perf_counter() - start, done.returncode, lines[-1] if lines else ""


def _exported(path: Path) -> tuple[list[str], np.ndarray]:
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    return lines[0].split(","), np.loadtxt(lines[1:], delimiter=",")


def _independent_check(config: Path, csv: Path) -> tuple[float, float, float, float, float]:
    """Largest position, velocity and torque use of the URDF's limits (1 = at the limit), the lowest
    clearance [m] of a checked link's geometry above the plane, and of the links the config ignores."""
    problem = load_problem(config)
    share = example_robot_data_root()
    urdf = str(share / "example-robot-data" / "robots" / problem.robot.urdf)
    model = open_source(Path(urdf)).model()  # continuous joints as revolute: one angle each, as the export writes them
    geometry = pin.buildGeomFromUrdf(model, urdf, pin.COLLISION, package_dirs=[str(share)])
    data, gdata = model.createData(), pin.GeometryData(geometry)
    header, table = _exported(csv)
    n = len(problem.robot.active_joints)
    q_idx = [model.idx_qs[model.getJointId(j)] for j in problem.robot.active_joints]
    v_idx = [model.idx_vs[model.getJointId(j)] for j in problem.robot.active_joints]
    lower, upper = model.lowerPositionLimit[q_idx], model.upperPositionLimit[q_idx]
    for k, joint in enumerate(problem.robot.active_joints):  # a continuous joint: the config's range
        lower[k], upper[k] = problem.robot.joint_ranges.get(joint, (lower[k], upper[k]))
    q, qd, qdd = (table[:, 1 + k * n : 1 + (k + 1) * n] for k in range(3))
    position = np.max(np.abs(q - (lower + upper) / 2) / ((upper - lower) / 2))
    velocity = np.max(np.abs(qd) / model.velocityLimit[v_idx])
    q_full = pin.neutral(model)
    for name, value in problem.robot.locked_joints.items():
        q_full[model.idx_qs[model.getJointId(name)]] = value
    plane = coal.Halfspace(np.array([0.0, 0.0, 1.0]), problem.constraints.environment.shapes[0].point[2])
    ignored = set(problem.constraints.environment.ignore_links)
    torque, checked, skipped = 0.0, np.inf, np.inf
    for t in range(0, len(table), 5):  # every 50 ms
        x, v, a = q_full.copy(), np.zeros(model.nv), np.zeros(model.nv)
        x[q_idx], v[v_idx], a[v_idx] = q[t], qd[t], qdd[t]
        tau = pin.rnea(model, data, x, v, a)[v_idx]
        torque = max(torque, float(np.max(np.abs(tau) / model.effortLimit[v_idx])))
        pin.updateGeometryPlacements(model, data, geometry, gdata, x)
        for k, g in enumerate(geometry.geometryObjects):
            if g.parentJoint == 0:
                continue
            result = coal.DistanceResult()
            placed = coal.Transform3s(gdata.oMg[k].rotation, gdata.oMg[k].translation)
            coal.distance(g.geometry, placed, plane, coal.Transform3s(), coal.DistanceRequest(), result)
            link = model.frames[g.parentFrame].name
            if link in ignored:
                skipped = min(skipped, result.min_distance)
            else:
                checked = min(checked, result.min_distance)
    return position, velocity, torque, checked, skipped


def main() -> None:
    print(
        f"{'robot':<12}{'joints':>7}{'excluded':>9}{'init':>7}{'check':>7}{'optimize':>10}{'cond(C)':>10}"
        f"{'q use':>7}{'q̇ use':>7}{'τ use':>7}{'plane [cm]':>11}{'ignored [cm]':>13}"
    )
    warnings: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name, urdf in ROBOTS.items():
            config = folder / f"{Path(urdf).stem}.yaml"
            t_init = _run(["init", urdf, "-o", str(config)], folder)[0]
            t_check = _run(["check", str(config)], folder)[0]
            result = folder / f"{Path(urdf).stem}.h5"
            t_opt, status, last = _run(["optimize", str(config), "--iterations", "1", "-o", str(result)], folder)
            csv = folder / f"{Path(urdf).stem}.csv"
            _run(["export", str(result), "--rate", "100", "-o", str(csv)], folder)
            if status:
                warnings.append(f"{name}: optimize exit {status}: {last}")
            with h5py.File(result) as f:
                cond = float(f["table"]["cond_stacked"][-1])
            problem = load_problem(config)
            position, velocity, torque, checked, skipped = _independent_check(config, csv)
            print(
                f"{name:<12}{len(problem.robot.active_joints):>7}"
                f"{len(problem.constraints.self_collision.exclude_pairs):>9}{t_init:>6.0f}s{t_check:>6.0f}s"
                f"{t_opt:>9.0f}s{cond:>10.1f}{position:>7.2f}{velocity:>7.2f}{torque:>7.2f}{checked * 100:>11.1f}"
                f"{skipped * 100 if np.isfinite(skipped) else float('nan'):>13.1f}"
            )
    for line in warnings:
        print(line)


if __name__ == "__main__":
    main()
