"""Which criterion gives the best identification? Trajectories optimized with each objective
(cond, log_cond, log_det = D-optimality, sigma_min = E-optimality) on a problem (default
configs/panda_joint_limits.yaml, first iteration), then identified on simulated measurements.

Simulation: one period sampled at 200 Hz, torques from pinocchio's RNEA with the URDF inertias plus
white noise (0.05 Nm); base parameters by least squares with the base regressor; 200 noise draws.
Printed per criterion: cond(C), the excitation ē that does not depend on the base columns
(:mod:`excite_cli.optimization.information`; log ē is the D-optimal criterion up to a constant), and over the base parameters the median and largest standard
deviation of the estimates, and the median relative standard deviation (std / |φ_B|, parameters with
|φ_B| > 1e-3), with the largest bias (mean estimate − truth) as a check that the estimates are unbiased.

Run: `.venv/bin/python bench/criteria.py [CONFIG]`. Prints a table; asserts nothing.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from excite_cli.config_file import load_problem
from excite_cli.optimization.criterion import OBJECTIVES, condition_number
from excite_cli.optimization.engine import Engine, default_workers
from excite_cli.optimization.excitation import build_excitation
from excite_cli.optimization.sequence import run_sequence

ROOT = Path(__file__).resolve().parent.parent
NOISE = 0.05  # Nm
RATE = 200.0  # Hz
DRAWS = 200


def identification_spread(
    excitation, alpha: np.ndarray, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Estimates' standard deviation and bias (b,), and the true base parameters (b,)."""
    robot = excitation.robot
    basis = excitation.trajectory.basis(np.arange(0.0, excitation.problem.trajectory.duration, 1.0 / RATE))
    Q, QD, QDD = basis.evaluate(alpha)
    Y = robot.regressor_stack(Q, QD, QDD)[:, excitation.base.independent]
    tau = np.concatenate([robot.torques(*x) for x in zip(Q, QD, QDD)])
    truth = excitation.base.from_standard(robot.urdf_parameters())
    noisy = tau[None, :] + rng.normal(0.0, NOISE, (DRAWS, tau.size))
    estimates = np.linalg.lstsq(Y, noisy.T, rcond=None)[0].T  # (draws, b)
    return estimates.std(axis=0), estimates.mean(axis=0) - truth, truth


def main(config: Path) -> None:
    print(
        f"{'objective':<10} {'cond(C)':>8} {'e [Nm]':>8} {'median std':>11} {'largest std':>12} {'median rel. std':>16} {'largest bias':>13}"
    )
    for objective in OBJECTIVES:
        problem = load_problem(config)
        problem.optimizer.objective = objective
        excitation = build_excitation(problem)
        with Engine(excitation, min(default_workers(), problem.optimizer.restarts)) as engine:
            result = run_sequence(excitation, 1, problem.optimizer.seed, engine=engine)[0]
        std, bias, truth = identification_spread(excitation, result.alpha, np.random.default_rng(0))
        relevant = np.abs(truth) > 1e-3
        print(
            f"{objective:<10} {condition_number(result.regressor):>8.1f} {result.excitation_own:>8.4g} {np.median(std):>11.2e} {std.max():>12.2e} "
            f"{np.median(std[relevant] / np.abs(truth[relevant])):>16.2%} {np.abs(bias).max():>13.1e}",
            flush=True,
        )


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "configs" / "panda_joint_limits.yaml")
