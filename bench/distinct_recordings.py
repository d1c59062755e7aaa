"""Sets of distinct recordings for `bench/identify_transfer.py`: several trajectories, each recorded
twice with its own noise (the twins named as one trajectory, so the folds hold them out together),
and one more trajectory for validation; or one periodic run. In MuJoCo's arm (`bench/mujoco_arm.py`)
on random feasible trajectories of the smoke problem, or in excite's simulator on an optimize
result's iterations."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mujoco_arm import ArmPhysics, arm_model, play

from excite_cli.config import RobotConfig
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.robot import load_robot
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.workflows.simulate import simulate_runs

ROOT = Path(__file__).resolve().parent.parent


def mujoco_twins(
    folder: Path, name: str, robot: dict, physics: ArmPhysics, trajectories: int = 4, periods: int = 1, seed: int = 0
) -> list[dict]:
    """``trajectories`` random feasible trajectories of the smoke problem played twice each in MuJoCo's
    arm with ``physics`` (roles ``fit``, named per trajectory) and one more played once (``validation``);
    with ``trajectories`` 1 and no twin, one periodic run of ``periods`` periods. The ``data.runs``."""
    smoke = build_excitation(load_problem(ROOT / "configs" / "smoke.yaml"))
    model_robot = load_robot(RobotConfig(**robot), joint_rows_only=True)
    mujoco, model = arm_model(resolve_urdf(RobotConfig(**robot))[0], model_robot.joint_names, physics)
    rng = np.random.default_rng(seed)
    twins = 2 if trajectories > 1 else 1
    runs = []
    for k in range(trajectories + 1):
        alpha = smoke.random_start(rng)
        fitted = k < trajectories
        for r in range(twins if fitted else 1):
            path = play(
                mujoco, model, model_robot, smoke.trajectory, alpha, periods, rng, folder / f"{name}_{k}_{r}.csv"
            )
            runs.append({"file": str(path), "role": "fit" if fitted else "validation", "trajectory": f"t{k}"})
    return runs


def simulated_twins(folder: Path, name: str, result: Path, effects: dict) -> list[dict]:
    """Every iteration of the optimize ``result`` simulated twice by ``excite simulate`` with ``effects``
    (0.05 Nm torque noise, seeds 1 and 2), the twins named per iteration; the last iteration once, for
    validation. The ``data.runs``."""
    runs = []
    for seed in (1, 2):
        sim = SimulationConfig(
            sample_rate=200, periods=1, torque_noise=0.05, position_noise=2e-4, seed=seed, effects=effects
        )
        simulate_runs(result, sim, folder / f"{name}_{seed}")
        paths = sorted((folder / f"{name}_{seed}").glob("run_*.csv"), key=lambda p: int(p.stem.split("_")[1]))
        for k, path in enumerate(paths, start=1):
            last = k == len(paths)
            if not (last and seed == 2):
                runs.append({"file": str(path), "role": "validation" if last else "fit", "trajectory": f"t{k}"})
    return runs
