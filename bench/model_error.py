"""How well the spread between trajectories is predicted from one fit: a Panda whose joint 2 has a
spring (and a quadratic term) the model lacks, recorded on many distinct random trajectories (excite's
own rigid-body regressor, friction in the model, torque noise 0.05 N·m). Disjoint sets of 4
trajectories are fitted by least squares; per base parameter, the RMS of each form's standard
deviation over the sets against the spread of the estimates over the sets:

- noise-only: σ² (AᵀA)⁻¹ (the model taken as right);
- CR1: the cluster-robust sandwich by trajectory, times G/(G−1);
- CR3: the jackknife over trajectories;
- CR2: each trajectory's residuals through (I − H_gg)^(-1/2), what identify reports
  (:mod:`excite_cli.identification.fitting.model_error`).

Run: `.venv/bin/python bench/model_error.py [SETS]` (default 30, seeds 0–2). Prints the median ratio
and the share of base parameters within 0.7–1.4 per form and seed; asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import sys
from pathlib import Path

import numpy as np

from excite_cli.config_file import load_problem
from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.robot import load_robot
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import least_squares
from excite_cli.identification.fitting.model_error import between_trajectories, trajectory_pieces
from excite_cli.identification.fitting.normal import NormalEquations, covariance_diagonal

ROOT = Path(__file__).resolve().parent.parent
#: Trajectories per set; torque noise [Nm]; the spring the model lacks [Nm/rad]; instants per recording
#: (50 Hz, 10 s).
PER_SET, NOISE, SPRING, INSTANTS = 4, 0.05, 15.0, 500


def panda():
    """The smoke config's Panda as identify loads it, and its base parameters."""
    problem = load_problem(ROOT / "configs" / "smoke.yaml")
    robot = load_robot(problem.robot, problem.folder, joint_rows_only=True, physical=False)
    return robot, compute_base_parameters(robot)


def motion(rng: np.random.Generator, n: int):
    """A random 5-harmonic motion of period 10 s about the middle of the range: q, q̇, q̈ (T, n)."""
    t = np.arange(INSTANTS) * 0.02
    w = 2 * np.pi / 10.0 * np.arange(1, 6)
    a, b = rng.normal(0, 0.12, (2, n, 5)) / np.arange(1, 6)
    s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
    return s @ a.T + c @ b.T, (c * w) @ a.T - (s * w) @ b.T, -(s * w**2) @ a.T - (c * w**2) @ b.T


def recording(robot, base, moving, rng: np.random.Generator):
    """Base regressor rows, torques with friction, the spring and noise, and the friction columns."""
    q, qd, qdd = moving
    n = robot.n_joints
    Y = robot.regressor_stack(q, qd, qdd)[:, base.independent]
    tau = (Y @ base.from_standard(robot.urdf_parameters())).reshape(-1, n) + 0.8 * np.tanh(qd / 0.01) + 0.3 * qd
    tau[:, 1] += SPRING * q[:, 1] + 4.0 * q[:, 1] ** 2  # the model lacks it
    tau += rng.normal(0, NOISE, tau.shape)
    blocks = {Term("coulomb", j): np.tanh(qd[:, j : j + 1] / 0.01) for j in range(n)}
    blocks.update({Term("viscous", j): qd[:, j : j + 1] for j in range(n)})
    return Y, tau.ravel(), blocks


def pooled(robot, recordings) -> tuple[Dataset, list[Term]]:
    """The recordings as one dataset, each its own run, and the model's friction terms."""
    terms = [Term(e, j) for e in ("coulomb", "viscous") for j in range(robot.n_joints)]
    data = Dataset(
        np.vstack([r[0] for r in recordings]),
        np.concatenate([r[1] for r in recordings]),
        np.arange(INSTANTS * len(recordings)) * 0.02,
        np.repeat(np.arange(len(recordings)), INSTANTS),
        {t: np.vstack([r[2][t] for r in recordings]) for t in terms},
    )
    return data, terms


def forms(data: Dataset, terms: list[Term], trajectory: np.ndarray) -> dict[str, np.ndarray]:
    """The estimates and each form's variances (module docstring)."""
    normal = NormalEquations(data, terms)
    fit = least_squares(normal, terms)
    grams, scores = trajectory_pieces(data, fit.x, terms, None, trajectory)
    total, count = grams.sum(axis=0), len(scores)
    shifts = np.array([np.linalg.pinv(total - Gg) @ s for Gg, s in zip(grams, scores)])  # x − x₋g
    return {
        "x": fit.x,
        "noise-only": fit.std**2,
        "CR1": covariance_diagonal(total, count / (count - 1) * scores.T @ scores),
        "CR3": (count - 1) / count * ((shifts - shifts.mean(axis=0)) ** 2).sum(axis=0),
        "CR2": between_trajectories(data, fit.x, terms, None, trajectory),
    }


def main(sets: int) -> None:
    robot, base = panda()
    b = base.count
    print(f"{sets} disjoint sets of {PER_SET} trajectories; per form: median ratio to the spread, share in 0.7–1.4")
    for seed in (0, 1, 2):
        rng = np.random.default_rng(seed)
        runs = []
        for _ in range(sets):
            data, terms = pooled(robot, [recording(robot, base, motion(rng, robot.n_joints), rng) for _ in range(4)])
            runs.append(forms(data, terms, np.arange(PER_SET)))
        x = np.array([r["x"][:b] for r in runs])
        spread = x.std(axis=0, ddof=1)
        resolved = spread > 1e-6 * np.abs(x).mean(axis=0)
        line = []
        for name in ("noise-only", "CR1", "CR3", "CR2"):
            ratio = np.sqrt(np.mean([r[name][:b] for r in runs], axis=0))[resolved] / spread[resolved]
            line.append(f"{name} {np.median(ratio):.2f} ({np.mean((ratio > 0.7) & (ratio < 1.4)):.0%})")
        print(f"seed {seed}: " + ", ".join(line))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 30)
