"""A coupled wrist identified (issue 32): a UR5 whose motor 6 turns with q5 + q6, every motor with its
rotor inertia and Coulomb and viscous friction (the motor's own values, acting through the
transmission m = R q, τ = Rᵀ τ_m), simulated by `excite simulate` from an optimized trajectory and
identified three ways:

- motor-side data (motor angles and torques) with the transmission declared;
- the same converted to the joint side, nothing declared (the search proposes couplings between
  neighbouring joints);
- joint-side data of the same arm without the coupling (every motor drives its own joint), nothing
  declared: no coupling should be proposed.

Printed: the coupled motor's coefficients (inertia, Coulomb, viscous: one effect) against the truth, the couplings found, the mean relative
validation error of the identified model and of the true model fitted on the same data.

    .venv/bin/python bench/coupled_wrist.py
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import tempfile
from pathlib import Path

import numpy as np
import yaml

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.robot import load_robot
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.least_squares import joint_weights, least_squares, predict, torque_errors
from excite_cli.identification.fitting.normal import NormalEquations
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.prepared import prepare_data
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.search.sequence import run_sequence
from excite_cli.storage.results import write_result
from excite_cli.workflows.simulate import simulate_runs

JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
ROBOT = {"urdf": "ur_description/urdf/ur5_robot.urdf", "source": "example-robot-data", "active_joints": JOINTS}
N = 101.0
TRUTH = {"armature": 2e-5, "coulomb": 0.01, "viscous": 2e-5}
MOTOR = {"armature": "Ia", "coulomb": "Fc", "viscous": "Fv"}  # a coupled motor's coefficients


def coupling(coupled: bool) -> np.ndarray:
    C = np.eye(6)
    C[5, 4] = 1.0 if coupled else 0.0
    return C


def true_error(problem: IdentifyProblem, terms: list[Term], live: np.ndarray | None = None) -> float:
    """Mean relative validation error [%] (over the ``live`` joints) of the model [Y_B, ``terms``]
    fitted by weighted least squares on the fit data of ``problem`` (joints not live get weight 0)."""
    robot = load_robot(problem.robot, problem.folder, joint_rows_only=True)
    data = prepare_data(problem, robot, compute_base_parameters(robot), terms)
    normal = NormalEquations(data.fit, terms)
    live = np.ones(data.fit.n, dtype=bool) if live is None else np.asarray(live)
    weights = joint_weights(normal, True) * live
    fit = least_squares(normal, terms, weights)
    measured = data.validation.tau.reshape(-1, data.validation.n)
    return float(torque_errors(measured, predict(data.validation, fit.x, terms))[2][live].mean())


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        config = {
            "robot": ROBOT,
            "trajectory": {
                "harmonics": 4,
                "base_frequency": 0.5,
                "cost_samples": 30,
                "cost_period": 0.3,
                "constraint_period": 0.05,
            },
            "limits": {"position_margin": 0.1, "acceleration": 4.0, "velocity": 2.0},
            "optimizer": {"max_iterations": 60, "restarts": 3},
            "noise": {"absolute": 0.1},  # every row the same, as the figures were measured (not the hedge)
            "sequence": {"iterations": 3},
        }
        (folder / "ur5.yaml").write_text(yaml.safe_dump(config))
        problem = load_problem(folder / "ur5.yaml")
        excitation = build_excitation(problem)
        write_result(folder / "ur5.h5", excitation, run_sequence(excitation, 3, 0), 0)
        cases = (
            ("motor side, transmission declared", True, True),
            ("joint side, nothing declared", True, False),
            ("joint side, no coupling in the data", False, False),
        )
        print(
            f"{'data':<38} {'couplings found':<48} {'coupled coefficients / truth':<34} {'validation error':>17} {'true model':>11}"
        )
        for name, coupled, motor_side in cases:
            C = coupling(coupled)
            transmission = {"gear_ratios": [N] * 6, "coupling": C.tolist()}
            sim = SimulationConfig(
                sample_rate=500,
                periods=4,
                torque_noise=0.002 if motor_side else 0.2,
                seed=3,
                motor_effects={e: {"*": v} for e, v in TRUTH.items()},
                transmission=transmission,
                motor_side=motor_side,
            )
            runs = folder / name.replace(" ", "_").replace(",", "")
            simulate_runs(folder / "ur5.h5", sim, runs)
            data = {
                "runs": [
                    {"file": str(runs / f"run_{k}.csv"), "role": r}
                    for k, r in ((1, "fit"), (2, "fit"), (3, "validation"))
                ],
                "columns": {"q": [f"q_{j}" for j in JOINTS], "tau": [f"tau_{j}" for j in JOINTS]},
            }
            if motor_side:
                data.update(transmission=transmission, motor_side=True)
            (runs / "id.yaml").write_text(
                yaml.safe_dump(
                    {
                        "robot": ROBOT,
                        "data": data,
                        "identification": {"fit": "least_squares"},
                        "output": str(runs / "id.h5"),
                    }
                )
            )
            identify = load_problem(runs / "id.yaml", IdentifyProblem)
            report, *_ = run_identification(identify)
            found = sorted({t.label(JOINTS) for t in report.selection.terms if t.coupling is not None})
            values = {c: v for t, c, v, _ in report.effect_values() if t.coupling is not None}
            ratios = (
                ", ".join(f"{e} {values[c] / TRUTH[e]:.4f}" for e, c in MOTOR.items() if c in values)
                if motor_side
                else ""
            )
            motor = tuple(N * C[5]) if motor_side else (0, 0, 0, 0, 1.0, 1.0)
            own = [Term(e, j) for e in TRUTH for j in range(5 if coupled else 6)]
            truth = own + ([Term("motor", 4, None, motor)] if coupled else [])
            print(
                f"{name:<38} {'; '.join(found) or 'none':<48} {ratios:<34} {report.relative_after.mean():>16.2f}% "
                f"{true_error(identify, truth):>10.2f}%",
                flush=True,
            )


if __name__ == "__main__":
    main()
