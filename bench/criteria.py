"""Which criterion identifies best? Each criterion's sequential trajectories identified in the loop.

For each criterion (``optimizer.objective`` with ``optimizer.scaling``) the config's sequence is
optimized (its iterations, restarts and screening; one process per core), and so is a random
baseline (the same number of random feasible starts, each the start the optimizer would draw).
Then, for 5 noise seeds:

- measurements: every trajectory of the sequence sampled at 100 Hz over its duration, torques from
  pinocchio's RNEA with the URDF's inertias plus white noise: ``--noise absolute`` (default) 2 % of
  each joint's RMS torque on the unseen motion (a torque sensor's noise does not depend on the motion,
  so every criterion gets the same); ``--noise relative`` σ_j(t) = √(s_j² + (0.02 τ_j(t))²), a noise
  growing with the torque (a motor current's) with a floor s_j of 0.2 % of that RMS; every criterion
  designs for the noise of the measurements, as a lab declares its sensor (the config's
  ``noise: {absolute: s_j, relative: 0 or 0.02}``);
- identification: weighted least squares of the base parameters on all of them (weights 1/σ);
- parameter error: the RMS over the b identifiable directions of L⁻¹(β̂ − β), the error in an
  orthonormal basis of the identifiable subspace of the standard parameters each scaled by its URDF
  magnitude (:mod:`excite_cli.design.information`; a value of 1 is an error as large as the
  parameters themselves), and the largest such direction error; beside it the error the noise
  gives on average, without drawing any: √(trace(L⁻¹ (YᵀWᵀWY)⁻¹ L⁻ᵀ)/b), W the weights (the
  standard deviations of weighted least squares; one seed's trajectories are then judged by what they
  are, not by 5 draws of noise);
- torque error: the identified model's torques on an unseen motion (a random feasible trajectory of
  the same problem, seed 12345, not in any sequence) against the true ones, relative RMS per joint,
  mean over joints.

Printed per criterion: cond(C) on the base columns and cond(C L) (the condition number that does
not depend on the base columns) after the last iteration, ē, the mean errors over the noise seeds
and the optimization's wall time.

Run: `.venv/bin/python bench/criteria.py [CONFIG ...] [--criteria OBJECTIVE:SCALING ...] [--seeds S ...] [--noise absolute|relative|both] [--design-noise D]`
(default the G1 arms and the Panda with joint limits, every criterion and random, seed 0; figures are
means over the seeds). Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import time
from pathlib import Path

import numpy as np
from maximin import maximin_sequence  # bench/ on the path, as a script has it

from excite_cli.config import NoiseConfig
from excite_cli.config_file import load_problem
from excite_cli.design.criterion import condition_number
from excite_cli.design.noise import typical_torques
from excite_cli.design.resolve import build_excitation
from excite_cli.search.engine import Engine, default_workers
from excite_cli.search.restarts import RestartTask
from excite_cli.search.sequence import run_sequence

ROOT = Path(__file__).resolve().parent.parent
CRITERIA = (
    ("log_cond", "none"),
    ("log_cond", "urdf"),
    ("sigma_min", "urdf"),
    ("log_det", "none"),
    ("log_trace_inverse", "none"),
    ("log_trace_inverse", "urdf"),
)
DEFAULT_CONFIGS = [ROOT / "configs" / "g1_arms.yaml", ROOT / "configs" / "panda_joint_limits.yaml"]
RATE = 100.0  # Hz
NOISE = 0.02  # of each joint's RMS torque on the unseen motion (absolute), or of the torque (relative)
FLOOR = 0.002  # the relative noise's floor, of each joint's RMS torque on the unseen motion
SEEDS = 5
UNSEEN_SEED = 12345


def samples(excitation, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Base regressor (T·n, b) and RNEA torques (T, n) of α sampled at ``RATE`` over its duration."""
    robot = excitation.robot
    basis = excitation.trajectory.basis(np.arange(0.0, excitation.spec.trajectory.duration, 1.0 / RATE))
    Q, QD, QDD = basis.evaluate(alpha)
    Y = robot.regressor_stack(Q, QD, QDD)[:, excitation.base.independent]
    return Y, np.array([robot.torques(*x) for x in zip(Q, QD, QDD)])


def noise_scale(excitation, relative: bool) -> tuple[np.ndarray, float]:
    """The absolute noise (n_rows,) [Nm, N] and the part relative to the torque [1] of the measurements
    (a floating base's wrench rows first, then the joints')."""
    _, tau_unseen = samples(excitation, excitation.random_start(np.random.default_rng(UNSEEN_SEED)))
    rms = np.sqrt((tau_unseen**2).mean(axis=0))
    return (FLOOR * rms, NOISE) if relative else (NOISE * rms, 0.0)


def in_the_loop(
    excitation, alphas: list[np.ndarray], unseen: np.ndarray, relative: bool
) -> tuple[float, float, float, float]:
    """Mean over noise seeds of the RMS and largest scaled parameter error, and the unseen torque error;
    and the RMS parameter error the noise gives on average (predicted, no noise drawn)."""
    truth = excitation.base.from_standard(excitation.robot.urdf_parameters())
    Y_unseen, tau_unseen = samples(excitation, unseen)
    absolute, rho = noise_scale(excitation, relative)
    data = [samples(excitation, a) for a in alphas]
    Y = np.vstack([y for y, _ in data])
    tau = np.vstack([t for _, t in data])
    sigma = np.sqrt(absolute**2 + (rho * tau) ** 2)  # (samples, n)
    weights = 1.0 / sigma.ravel()
    inverse_frame = np.linalg.inv(excitation.scaled_frame)
    covariance = inverse_frame @ np.linalg.inv((Y * weights[:, None]).T @ (Y * weights[:, None])) @ inverse_frame.T
    expected = float(np.sqrt(np.trace(covariance) / covariance.shape[0]))
    rms, worst, torque = [], [], []
    for seed in range(SEEDS):
        noisy = tau + np.random.default_rng(seed).normal(0.0, 1.0, tau.shape) * sigma
        estimate = np.linalg.lstsq(Y * weights[:, None], noisy.ravel() * weights, rcond=None)[0]
        error = inverse_frame @ (estimate - truth)
        rms.append(np.sqrt(np.mean(error**2)))
        worst.append(np.abs(error).max())
        predicted = (Y_unseen @ estimate).reshape(tau_unseen.shape)
        torque.append(np.mean(np.sqrt(((predicted - tau_unseen) ** 2).mean(axis=0) / (tau_unseen**2).mean(axis=0))))
    return float(np.mean(rms)), float(np.mean(worst)), float(np.mean(torque)), expected


def design_noise(problem, design: str, relative: bool) -> None:
    """Set ``problem.noise`` to what the design is told: ``measured`` the measurements' own noise (a lab
    that declares its sensor), ``config`` what the config says, ``default`` nothing (the config's
    ``noise`` removed: what excite designs for when a lab declares nothing, the hedge), ``equal`` every
    row the same (``noise: {absolute: 0.1}``, the default before the hedge), ``hedge:K``
    σ_j(t) ∝ √((K R_j)² + τ_j(t)²), R_j the typical torque of joint j as the default takes it
    (:func:`~excite_cli.design.noise.typical_torques`: random feasible motions, not the unseen one);
    ``maximin`` (``maximin:sequence``) or ``maximin:iteration``, the maximin-efficiency design over an
    absolute and a relative model, normalized by each model's own sequence or by each model's optimum
    at each iteration, or ``compound:W`` the weighted mean of the two models' log criteria, W the
    absolute model's weight (bench/maximin.py; it sets its models itself)."""
    if design == "config" or design.startswith(("maximin", "compound")):  # maximin: the models are bench/maximin.py's
        return
    if design == "default":
        problem.noise = None
        return
    if design == "equal":
        problem.noise = NoiseConfig(absolute=0.1)  # every row the same (the shipped configs' declaration)
        return
    excitation = build_excitation(problem)
    joints = problem.robot.active_joints
    if design == "measured":
        absolute, rho = noise_scale(excitation, relative)
        problem.noise = NoiseConfig(absolute=dict(zip(joints, absolute[-len(joints) :].tolist())), relative=rho)
        return
    k = float(design.split(":")[1])
    typical = typical_torques(excitation)  # R_j as the default's hedge takes them: hedge:0.5 is the default
    problem.noise = NoiseConfig(absolute=dict(zip(joints, (k * typical).tolist())), relative=1.0)


def run(config: Path, objective: str, scaling: str, seed: int, truths: list[bool], design: str) -> list[tuple]:
    """The sequence of one criterion (or the random starts) with optimizer seed ``seed``, designed for
    ``design`` (:func:`design_noise`; ``measured``: for the one truth in ``truths``), its figures under
    each truth (relative noise or not) and its wall time."""
    problem = load_problem(config)
    problem.optimizer.objective, problem.optimizer.scaling, problem.optimizer.seed = objective, scaling, seed
    design_noise(problem, design, truths[0])
    excitation = build_excitation(problem)
    begin = time.perf_counter()
    iterations = problem.sequence.iterations
    if design.startswith("compound"):
        alphas = maximin_sequence(problem, seed, 1, design)
    elif design.startswith("maximin"):
        workers = min(default_workers(), problem.optimizer.screened or problem.optimizer.restarts)
        alphas = maximin_sequence(problem, seed, workers, design.partition(":")[2] or "sequence")
    elif objective == "random":
        prior = np.zeros((0, excitation.base.count))
        alphas = [excitation.random_start(RestartTask(k, 1, seed, prior).rng()) for k in range(1, iterations + 1)]
    else:
        workers = min(default_workers(), problem.optimizer.screened or problem.optimizer.restarts)
        with Engine(excitation, workers) as engine:
            alphas = [r.alpha for r in run_sequence(excitation, iterations, seed, engine=engine)]
    wall = time.perf_counter() - begin
    C = np.vstack(
        [excitation.criterion(objective="log_cond", scaling="none", weighed=False).regressor(a) for a in alphas]
    )
    unseen = excitation.random_start(np.random.default_rng(UNSEEN_SEED))
    figures = (condition_number(C), excitation.scaled_condition_number(C), excitation.excitation_level(C))
    return [(*figures, *in_the_loop(excitation, alphas, unseen, relative), wall) for relative in truths]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("configs", type=Path, nargs="*", default=DEFAULT_CONFIGS)
    parser.add_argument("--criteria", nargs="+", default=[f"{o}:{s}" for o, s in CRITERIA] + ["random:none"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--noise", choices=("absolute", "relative", "both"), default="absolute")
    parser.add_argument(
        "--design-noise",
        default="measured",
        help="measured | config | default | equal | hedge:K | maximin[:iteration|:sequence] | compound:W",
    )
    args = parser.parse_args()
    truths = {"absolute": [False], "relative": [True], "both": [False, True]}[args.noise]
    if args.design_noise == "measured" and len(truths) > 1:
        parser.error("--noise both needs a design that does not depend on the truth (--design-noise config or hedge:K)")
    header = f"{'criterion':<22} {'cond(C)':>8} {'cond(CL)':>9} {'e [Nm]':>8} {'param err RMS':>14} {'worst dir.':>11} {'unseen torque':>14} {'predicted':>10} {'wall [s]':>9}"
    for config in args.configs:
        for criterion in args.criteria:
            objective, scaling = criterion.split(":")
            runs = [run(config, objective, scaling, seed, truths, args.design_noise) for seed in args.seeds]
            for k, relative in enumerate(truths):
                truth = "relative" if relative else "absolute"
                print(
                    f"\n{config.name}, {truth} noise, designed for {args.design_noise}, optimizer seeds {args.seeds} (means)\n{header}"
                )
                report(objective, scaling, np.array([r[k] for r in runs]), len(args.seeds))


def report(objective: str, scaling: str, rows: np.ndarray, seeds: int) -> None:
    """One criterion's line (means over the seeds) and, with several seeds, each seed's errors."""
    cond, scaled, level, rms, worst, torque, predicted, wall = rows.mean(axis=0)
    label = objective if objective in ("random", "log_det") else f"{objective}, {scaling}"
    print(
        f"{label:<22} {cond:>8.1f} {scaled:>9.0f} {level:>8.4f} {rms:>14.2%} {worst:>11.1%} {torque:>14.3%} {predicted:>10.3%} {wall:>9.0f}",
        flush=True,
    )
    if seeds > 1:
        print(
            f"{'  per seed':<22} param err {' '.join(f'{x:.2%}' for x in rows[:, 3])}; torque {' '.join(f'{x:.3%}' for x in rows[:, 5])}; "
            f"predicted {' '.join(f'{100 * x:.4g}%' for x in rows[:, 6])}"
        )


if __name__ == "__main__":
    main()
