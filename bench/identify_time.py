"""Time of `excite identify` on many recordings: a simulated UR5 (6 joints; excite's simulator, random
feasible trajectories of configs/ur5.yaml, each distinct, 10 s at 200 Hz per period, 0.2 mrad encoder
noise; truth ``lab`` (default): Coulomb 0.6 N·m and viscous 0.4 N·m·s/rad friction on every joint,
Stribeck friction on two joints, armature, offsets on two joints, torque noise 0.05 N·m + 1 % of the
torque; ``friction``: the friction and 0.05 N·m of noise only), N recordings fitted with nothing
declared (the default search) and one more for validation, identified in a child process: its wall
time, its CPU time (user + system, every thread) and the report's mean validation error, so that a
change of speed shows whether the figures moved.

`--code DIR` runs another checkout's `excite` (its package on the path) on the same files, so the
same recordings can be timed at an earlier commit (`git worktree add /tmp/old REV`).

Run: `.venv/bin/python bench/identify_time.py [--recordings 16] [--seed 0] [--truth lab|friction]
[--periods 1] [--code DIR]`. Prints one line; asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np
import yaml

from excite_cli.config import RobotConfig
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.search.sequence import describe
from excite_cli.storage.results import write_result
from excite_cli.workflows.simulate import simulate_runs

ROOT = Path(__file__).resolve().parent.parent
CONFIG = ROOT / "configs" / "ur5.yaml"
FRICTION = {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}}
TRUTHS = {
    "friction": {"torque_noise": 0.05, "effects": FRICTION},
    "lab": {
        "torque_noise": 0.05,
        "torque_noise_relative": 0.01,
        "effects": {
            **FRICTION,
            "stribeck": {"elbow_joint": 0.35, "wrist_1_joint": 0.2},
            "armature": {"*": 0.05},
            "offset": {"shoulder_lift_joint": 0.3, "wrist_2_joint": -0.1},
        },
    },
}


def recordings(folder: Path, count: int, seed: int, truth: str, periods: int) -> tuple[list[Path], RobotConfig]:
    """``count`` distinct random feasible trajectories of :data:`CONFIG`, simulated; and its robot."""
    problem = load_problem(CONFIG)
    excitation = build_excitation(problem)
    rng = np.random.default_rng(1000 + seed)
    prior = np.zeros((0, excitation.columns))
    results = [describe(excitation, k + 1, excitation.random_start(rng), prior) for k in range(count)]
    target = folder / "motions.h5"
    write_result(target, excitation, results, seed, {"method": "random_selection"})
    sim = SimulationConfig(sample_rate=200, periods=periods, position_noise=2e-4, seed=seed, **TRUTHS[truth])
    return simulate_runs(target, sim, folder / "runs"), problem.robot


def identify(folder: Path, runs: list[Path], robot: RobotConfig, code: Path) -> tuple[float, float, float]:
    """Wall and CPU time [s] of `excite identify` (``code``'s package) on ``runs`` (the last one
    validation) of ``robot``, and the report's mean relative validation error [%]."""
    joints = list(robot.active_joints)
    config = {
        "robot": {"urdf": robot.urdf, "source": robot.source, "active_joints": joints},
        "data": {
            "runs": [
                {"file": str(p), "role": "fit" if k < len(runs) - 1 else "validation"} for k, p in enumerate(runs)
            ],
            "columns": {"q": [f"q_{j}" for j in joints], "tau": [f"tau_{j}" for j in joints]},
        },
        "preprocessing": {"sample_rate": 200},
        "output": str(folder / "ident.h5"),
    }
    path = folder / "identify.yaml"
    path.write_text(yaml.safe_dump(config))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    env = {**os.environ, "PYTHONPATH": str(code)}
    result = subprocess.run(
        [sys.executable, "-m", "excite_cli", "identify", str(path), "--force"], capture_output=True, text=True, env=env
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if result.returncode != 0:
        raise SystemExit(result.stdout + result.stderr)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with h5py.File(folder / "ident.h5") as f:
        after_fit = np.asarray(f["identification/relative_after"])
    return wall, cpu, float(np.mean(after_fit))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--recordings", type=int, default=16)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--truth", choices=sorted(TRUTHS), default="lab")
    parser.add_argument("--periods", type=int, default=1, help="periods of each 10 s trajectory a recording plays")
    parser.add_argument("--code", type=Path, default=ROOT, help="the checkout whose excite_cli runs identify")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        runs, robot = recordings(folder, args.recordings + 1, args.seed, args.truth, args.periods)
        wall, cpu, error = identify(folder, runs, robot, args.code.resolve())
    print(
        f"{args.recordings} recordings, seed {args.seed}, {args.code}: wall {wall:.1f} s, CPU {cpu:.1f} s, "
        f"validation error {error:.4f} %"
    )


if __name__ == "__main__":
    main()
