"""The loop closed both ways: does designing the next trajectory for the effects identification found
identify them better? A simulated robot with friction and rotor inertia on every joint and one coupled
motor, for several seeds:

1. trajectory 1 optimized blind (the config's rigid-body design, one iteration), and measured: sampled at
   100 Hz over its duration, torques = RNEA with the URDF's inertias + the effects' true torques + white
   noise of 2 % of each joint's RMS torque on an unseen motion;
2. trajectory 2 of the same duration designed (a) blind, as today: iteration 2 of the rigid-body
   sequence (C₀ = trajectory 1's base-regressor rows), or (b) for the identified model: its effect columns
   beside the base columns (`effects`: Coulomb, viscous friction and armature on every joint, the
   coupled motor's inertia and friction) with trajectory 1's rows of that model as C₀; both from the
   same random starts (iteration 2's);
3. both measured as run 1 and identified together with run 1: weighted least squares (1/σ_j) of the base
   parameters and every effect coefficient, over ``NOISE_DRAWS`` draws of the noise (the errors are
   their means: one draw's error is itself noisy at the 10 % level).

The identified model is the true one (the effects a report of run 1 names; identify finds exactly these
on the shipped simulated Panda runs, tests), so what differs is the second trajectory alone. True
effect coefficients: each the typical magnitude of the design's scaling (its torque at the joint's
limits 5 % of the URDF's effort limit). Columns the base parameters already hold (a first joint's
armature) are neither simulated nor identified.

Printed per robot and seed: mean relative error of the effect coefficients [%], the base parameters'
error (RMS over the identifiable directions of L⁻¹(β̂ − β) in the URDF-scaled frame, as
bench/criteria.py) [%], the unseen motion's relative torque error [%] and the effects' predicted
relative standard deviation (from the weighted information matrix, no noise drawn) [%], (a) then (b);
and the last lines, one per robot: `loop ROBOT: effects error blind X %, designed Y %; base error blind
X %, designed Y %` (means over the seeds). ``--design`` designs (b) with another criterion (and
scaling), e.g. ``log_trace_inverse:urdf``, A-optimality in the URDF-scaled frame: the sum of the
relative variances. ``--effects-weight K`` divides the effect coefficients' magnitudes in that frame
by K, so each effect's relative variance counts K² times a base parameter's: how far a design that
asks for the effects above all can take them.

    .venv/bin/python bench/loop.py [--robots G1 Panda] [--seeds 0 1 2] [--design OBJECTIVE:SCALING]
        [--effects-weight K]

Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from excite_cli.config import EffectsConfig, MotorConfig
from excite_cli.config_file import load_problem
from excite_cli.design.excitation import build_design
from excite_cli.design.resolve import build_excitation
from excite_cli.search.engine import Engine, default_workers
from excite_cli.search.sequence import describe, run_sequence

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = {"G1": ROOT / "configs" / "g1_arms.yaml", "Panda": ROOT / "configs" / "panda_joint_limits.yaml"}
RATE, NOISE, UNSEEN_SEED, NOISE_DRAWS = 100.0, 0.02, 12345, 20


def measured(excitation, alpha: np.ndarray, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """[Y_B | Y_E] (T·n, b+e) and the true torques (T, n) of α sampled at ``RATE`` (no noise yet)."""
    robot, b = excitation.robot, excitation.base.count
    basis = excitation.trajectory.basis(np.arange(0.0, excitation.spec.trajectory.duration, 1.0 / RATE))
    Q, QD, QDD = basis.evaluate(alpha)
    Y = np.hstack(
        [robot.regressor_stack(Q, QD, QDD)[:, excitation.base.independent], excitation.effects.columns(QD, QDD)]
    )
    rigid = np.array([robot.torques(*x) for x in zip(Q, QD, QDD)])
    return Y, rigid + (Y[:, b:] @ truth[b:]).reshape(rigid.shape)


def identified(excitation, runs: list[tuple[np.ndarray, np.ndarray]], sigma: np.ndarray, seed: int) -> np.ndarray:
    """WLS estimates of [β; c] (b+e, ``NOISE_DRAWS``) from the runs' columns and torques, each with its
    own draw of white noise σ_j (n,)."""
    Y = np.vstack([y for y, _ in runs])
    tau = np.vstack([t for _, t in runs])
    noise = np.random.default_rng(seed).normal(0.0, 1.0, (NOISE_DRAWS, *tau.shape)) * sigma
    w = np.tile(1.0 / sigma, tau.shape[0])
    noisy = (tau[None] + noise).reshape(NOISE_DRAWS, -1).T * w[:, None]
    return np.linalg.lstsq(Y * w[:, None], noisy, rcond=None)[0]


def errors(
    excitation, estimates: np.ndarray, truth: np.ndarray, unseen: tuple[np.ndarray, np.ndarray], std: np.ndarray
) -> tuple:
    """Means over the draws ``estimates`` (b+e, draws) of the effect coefficients' mean relative error,
    the base parameters' scaled RMS error and the unseen torque error; and the effects' mean predicted
    relative standard deviation from ``std`` (b+e,)."""
    b = excitation.base.count
    effect = np.mean(np.abs(estimates[b:] - truth[b:, None]) / np.abs(truth[b:, None]))
    scaled = np.linalg.solve(excitation.scaled_frame[:b, :b], estimates[:b] - truth[:b, None])
    base = np.mean(np.sqrt(np.mean(scaled**2, axis=0)))
    Y, tau = unseen
    predicted = (Y @ estimates).T.reshape(-1, *tau.shape)
    torque = np.mean(np.sqrt(((predicted - tau) ** 2).mean(axis=1) / (tau**2).mean(axis=0)))
    return effect, base, torque, np.mean(std[b:] / np.abs(truth[b:]))


def predicted_std(runs: list[tuple[np.ndarray, np.ndarray]], sigma: np.ndarray) -> np.ndarray:
    """(b+e,) the estimates' standard deviations of weighted least squares on the runs' columns with
    noise σ_j (n,): the square roots of the diagonal of (YᵀWᵀWY)⁻¹."""
    Y = np.vstack([y for y, _ in runs])
    w = np.tile(1.0 / sigma, Y.shape[0] // sigma.size)
    return np.sqrt(np.diag(np.linalg.inv((Y * w[:, None]).T @ (Y * w[:, None]))))


def simulated_robot(config: Path, seed: int) -> tuple:
    """The config's problem with optimizer seed ``seed``: its blind excitation (rigid body only), the
    problem with the simulated robot's effects (Coulomb, viscous, armature on every joint, a motor
    coupled to the last two joints), that problem's excitation (the identified model's columns: those
    the base does not hold) and the true [β; c] (b+e,)."""
    problem = load_problem(config)
    problem.optimizer.seed = seed
    blind = build_excitation(problem)
    joints = problem.robot.active_joints
    design = problem.model_copy(deep=True)
    design.effects = EffectsConfig(
        joints={"*": ["coulomb", "viscous", "armature"]},
        motors=[MotorConfig(joints=joints[-2:], transmission=[1.0, 1.0])],
    )
    model = build_excitation(design)
    effort = model.robot.model.effortLimit[model.robot.v_idx]
    magnitudes = model.effects.magnitudes(effort, model.limits.upper[1], model.limits.upper[2])
    truth = np.concatenate([model.base.from_standard(model.robot.urdf_parameters()), magnitudes])
    return blind, design, model, truth


def blind_runs(blind, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """α of trajectory 1 and of (a)'s trajectory 2, iterations 1 and 2 of the blind sequence (n, 2N+1)."""
    with Engine(blind, min(default_workers(), blind.spec.optimizer.restarts)) as engine:
        first = run_sequence(blind, 1, seed, engine=engine)
        second = run_sequence(blind, 2, seed, engine=engine, finished=first)[-1].alpha
    return first[0].alpha, second


def noise_levels(model, truth: np.ndarray) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray]:
    """The unseen motion's columns and true torques, and each joint's noise σ_j (n,): ``NOISE`` of its
    RMS torque there."""
    unseen = measured(model, model.random_start(np.random.default_rng(UNSEEN_SEED)), truth)
    return unseen, NOISE * np.sqrt((unseen[1] ** 2).mean(axis=0))


def loop(config: Path, seed: int, design_criterion: tuple[str, str] | None = None, weight: float = 1.0) -> tuple:
    """(a) and (b)'s errors of one seed, and the wall time; (b) designed with ``design_criterion``
    (objective, scaling), default the config's, the effects' magnitudes in its frame divided by ``weight``."""
    begin = time.perf_counter()
    blind, design, model, truth = simulated_robot(config, seed)
    if design_criterion is not None:
        design.optimizer.objective, design.optimizer.scaling = design_criterion
    designer = build_excitation(design) if design_criterion is not None else model
    if weight != 1.0:
        emphasis = np.concatenate([np.ones(model.base.count), np.full(model.effects.count, 1.0 / weight)])
        designer = build_design(replace(designer.spec, scaled_frame=designer.scaled_frame * emphasis))
    alpha1, blind_second = blind_runs(blind, seed)
    workers = min(default_workers(), design.optimizer.restarts)  # workers build from the designer's spec
    with Engine(designer, workers) as engine:
        earlier = [describe(designer, 1, alpha1, np.zeros((0, designer.columns)))]
        designed_second = run_sequence(designer, 2, seed, engine=engine, finished=earlier)[-1].alpha
    unseen, sigma = noise_levels(model, truth)
    run1 = measured(model, alpha1, truth)
    rows = []
    for second in (blind_second, designed_second):
        runs = [run1, measured(model, second, truth)]
        rows.append(errors(model, identified(model, runs, sigma, seed), truth, unseen, predicted_std(runs, sigma)))
    return rows[0], rows[1], time.perf_counter() - begin


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=list(ROBOTS))
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--design", default=None, help="OBJECTIVE:SCALING of (b), e.g. log_trace_inverse:urdf")
    parser.add_argument("--effects-weight", type=float, default=1.0, help="K: (b)'s effect magnitudes divided by K")
    args = parser.parse_args()
    design = tuple(args.design.split(":")) if args.design else None
    lines = []
    for robot in args.robots:
        results = []
        for seed in args.seeds:
            a, b, wall = loop(ROBOTS[robot], seed, design, args.effects_weight)
            results.append((a, b))
            print(
                f"  {robot} seed {seed}: effects {a[0]:.3%} / {b[0]:.3%}, base {a[1]:.3%} / {b[1]:.3%}, "
                f"unseen torque {a[2]:.3%} / {b[2]:.3%}, predicted effect std {a[3]:.3%} / {b[3]:.3%} "
                f"(blind / designed), {wall:.0f} s",
                flush=True,
            )
        mean = np.mean(np.array(results), axis=0)  # (2, 4)
        lines.append(
            f"loop {robot}: effects error blind {mean[0, 0]:.3%}, designed {mean[1, 0]:.3%}; "
            f"base error blind {mean[0, 1]:.3%}, designed {mean[1, 1]:.3%}"
        )
    print("\n".join(lines))


if __name__ == "__main__":
    main()
