"""The spread between trajectories in MuJoCo's physics, which nobody here wrote: the Panda of
`bench/mujoco_arm.py` (joint damping, dry friction, armature, a payload) with a spring on joint 2
that the identification is not given (model error the candidate set does not hold). Each set is 4
random feasible trajectories of the smoke problem (3 harmonics, 10 s), each recorded twice
(independent noise); identify fits every set with one fixed model (Coulomb and viscous friction and
armature declared, no search), the twins named as one trajectory. Per base parameter, the RMS of the
reported standard deviations over the sets against the spread of the estimates over the sets: the
spread between trajectories (what identify reports beside the noise's) and the noise-only sandwich.

Run: `.venv/bin/python bench/trajectory_spread.py [SETS]` (default 12). Prints the median ratio and the
share of base parameters within 0.7–1.4 for both; asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml
from mujoco_arm import ArmPhysics, arm_model, play

from excite_cli.config import RobotConfig
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.robot import load_robot
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.pipeline import run_identification

ROOT = Path(__file__).resolve().parent.parent
PANDA = [f"panda_joint{k}" for k in range(1, 8)]
ROBOT = {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": PANDA}
PHYSICS = ArmPhysics(
    damping=np.array([0.6, 0.6, 0.5, 0.5, 0.2, 0.2, 0.1]),
    frictionloss=np.array([0.8, 0.8, 0.6, 0.6, 0.3, 0.3, 0.2]),
    armature=np.array([0.3, 0.3, 0.2, 0.2, 0.05, 0.05, 0.02]),
    payload=(1.0, (0.0, 0.0, 0.207), (2e-3, 2e-3, 1e-3)),
    stiffness=np.array([0.0, 20.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
)
#: Trajectories per set, recordings per trajectory.
PER_SET, TWICE = 4, 2


def identified(folder: Path, recordings: list[list[Path]]):
    """The least-squares fit of the recordings (per trajectory, its twins) with the fixed model."""
    runs = [
        {"file": str(p), "role": "blocks", "trajectory": f"t{k}"} for k, twins in enumerate(recordings) for p in twins
    ]
    config = {
        "robot": ROBOT,
        "data": {"runs": runs, "columns": {"q": [f"q_{j}" for j in PANDA], "tau": [f"tau_{j}" for j in PANDA]}},
        "identification": {
            "declared_effects": {"*": ["coulomb", "viscous", "armature"]},
            "candidates": [],
            "fit": "least_squares",
        },
        "output": str(folder / "r.h5"),
    }
    (folder / "identify.yaml").write_text(yaml.safe_dump(config))
    return run_identification(load_problem(folder / "identify.yaml", IdentifyProblem))[0]


def main(sets: int) -> None:
    smoke = build_excitation(load_problem(ROOT / "configs" / "smoke.yaml"))
    robot = load_robot(RobotConfig(**ROBOT), joint_rows_only=True)
    mujoco, model = arm_model(resolve_urdf(RobotConfig(**ROBOT))[0], robot.joint_names, PHYSICS)
    rng = np.random.default_rng(0)
    x, noise, between = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for s in range(sets):
            recordings = []
            for k in range(PER_SET):
                alpha = smoke.random_start(rng)
                recordings.append(
                    [
                        play(mujoco, model, robot, smoke.trajectory, alpha, 1, rng, folder / f"s{s}_t{k}_{r}.csv")
                        for r in range(TWICE)
                    ]
                )
            report = identified(folder, recordings)
            fit, b = report.selection.fit, len(report.base_names)
            x.append(fit.x[:b])
            noise.append(fit.std[:b])
            between.append(fit.between[:b])
            print(f"set {s + 1}/{sets}: {fit.trajectories} trajectories", flush=True)
    x = np.array(x)
    spread = x.std(axis=0, ddof=1)
    resolved = spread > 1e-6 * np.abs(x).mean(axis=0)
    for name, stds in (("noise-only sandwich", noise), ("between trajectories", between)):
        ratio = np.sqrt((np.array(stds) ** 2).mean(axis=0))[resolved] / spread[resolved]
        print(f"{name}: median {np.median(ratio):.2f}, within 0.7-1.4: {np.mean((ratio > 0.7) & (ratio < 1.4)):.0%}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 12)
