"""Headroom of bench/loop.py: how much lower could a second trajectory of the config's family make the
effect coefficients' predicted error if nothing else had to be identified?

The question is optimistic on purpose, so that its answer is a generous estimate of what design (b)
could reach at all:
- the base parameters are dropped (no rigid-body column competes with the effects), and so are the CoM,
  self-collision and environment constraints; what stays is the config's trajectory family (harmonics,
  base frequency, duration, rest at both ends) and its position, velocity and acceleration limits,
  enforced at the measurement grid;
- each joint's own effects (Coulomb, viscous, armature; the coupled motor together with the joints it
  turns) depend on those joints' motion alone, so each group's second-run Fourier coefficients are
  chosen for that group alone: they minimize the sum of its coefficients' relative standard deviations
  (what the mean relative error predicts) from run 1's rows of those columns plus run 2's, weighted
  by 1/σ_j as bench/loop.py identifies;
- SLSQP (SciPy) from run 1's coefficients, (a)'s and ``STARTS`` random starts; the best feasible end.

This is the best a multi-start local search found, not a proven optimum (searched with one BLAS thread:
the searches' paths are chaotic in the last bits, and so the same with any thread setting). The groups'
best motions together are one second run (each joint's coefficients from its group's best); identified
as bench/loop.py identifies, with the base parameters beside the effects, it shows how much of the
room the rigid-body columns leave.

Printed per robot and seed: the effect coefficients' mean predicted relative standard deviation [%]
with (a)'s second run (the rigid-body columns included, as bench/loop.py predicts it), with the best
second run found for the effects alone, and with that run identified with the base parameters; the last
lines, one per robot: `headroom ROBOT: effects std blind X %, best second run for the effects alone Y %
(Z % lower), identified with the base parameters W % (V % lower)` (means over the seeds);
``--coefficients`` each coefficient's std with (a)'s second run and with the best found.

    .venv/bin/python bench/loop_headroom.py [--robots G1 Panda] [--seeds 0 1 2] [--starts 12] [--coefficients]

Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import time

import numpy as np
from loop import RATE, ROBOTS, blind_runs, measured, noise_levels, predicted_std, simulated_robot
from scipy.optimize import minimize
from threadpoolctl import threadpool_limits

from excite_cli.trajectory.boundary import boundary_rows

STARTS = 12


def joint_groups(transmissions: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """(joints, columns) of the effect columns whose transmission rows (e, n) share joints, merged
    until no two groups share one: each joint's own effects, a coupled motor with its joints'."""
    groups = [({int(j) for j in np.flatnonzero(row)}, [c]) for c, row in enumerate(transmissions)]
    merged: list[tuple[set, list]] = []
    for joints, columns in groups:
        for other in [g for g in merged if g[0] & joints]:
            merged.remove(other)
            joints, columns = joints | other[0], other[1] + columns
        merged.append((joints, columns))
    return [(np.array(sorted(j)), np.array(sorted(c))) for j, c in merged]


def best_second_run(
    model, alphas: list[np.ndarray], sigma: np.ndarray, magnitudes: np.ndarray, seed: int, starts: int
) -> tuple[np.ndarray, np.ndarray]:
    """(e,) each effect coefficient's relative standard deviation with the best second run found for its
    group, and that run's coefficients (n, 2N+1) (each group's joints from its own best); ``alphas``:
    run 1's coefficients, then the other starts (n, 2N+1); ``starts`` random starts more per group;
    ``magnitudes`` (e,) the true coefficients' sizes."""
    duration = model.spec.trajectory.duration
    basis = model.trajectory.basis(np.arange(0.0, duration, 1.0 / RATE))
    ends = boundary_rows(model.trajectory, duration, model.spec.trajectory.boundary == "rest", False)
    lower, upper = model.limits.lower, model.limits.upper

    def information(alpha: np.ndarray, effects, scale: np.ndarray) -> np.ndarray:
        _, QD, QDD = basis.evaluate(alpha)
        Y = effects.columns(QD, QDD) * np.tile(1.0 / sigma, QD.shape[0])[:, None] * scale
        return Y.T @ Y

    out, combined = np.empty(model.effects.count), alphas[0].copy()
    rng = np.random.default_rng(seed)
    for joints, columns in joint_groups(model.effects.transmissions):
        keep = np.isin(np.arange(model.effects.count), columns)
        effects = model.effects.subset(keep)
        first = information(alphas[0], effects, magnitudes[keep])
        shape = (joints.size, model.trajectory.n_coefficients)

        def with_group(x: np.ndarray) -> np.ndarray:
            alpha = alphas[0].copy()
            alpha[joints] = x.reshape(shape)
            return alpha

        def deviations(x: np.ndarray) -> np.ndarray:
            both = first + information(with_group(x), effects, magnitudes[keep])
            return np.sqrt(np.diag(np.linalg.inv(both)))

        def inside(x: np.ndarray) -> np.ndarray:
            motion = basis.evaluate(with_group(x))
            span = (upper - lower)[:, joints]
            return np.concatenate(
                [((upper[d, joints] - m[:, joints]) / span[d]).ravel() for d, m in enumerate(motion)]
                + [((m[:, joints] - lower[d, joints]) / span[d]).ravel() for d, m in enumerate(motion)]
            )

        def at_rest(x: np.ndarray) -> np.ndarray:
            return (ends @ x.reshape(shape).T).ravel()

        constraints = [{"type": "ineq", "fun": inside}, {"type": "eq", "fun": at_rest}]
        points = [a[joints].ravel() for a in alphas] + [model.random_start(rng)[joints].ravel() for _ in range(starts)]
        best, best_x = np.inf, None
        for x0 in points:
            end = minimize(
                lambda x: float(np.sum(deviations(x))),
                x0,
                method="SLSQP",
                constraints=constraints,
                options={"maxiter": 300},
            )
            feasible = inside(end.x).min() > -1e-6 and np.abs(at_rest(end.x)).max(initial=0.0) < 1e-6
            if feasible and end.fun < best:
                best, best_x = end.fun, end.x
        out[columns] = deviations(best_x)
        combined[joints] = best_x.reshape(shape)
    return out, combined


def headroom(config, seed: int, starts: int, coefficients: bool = False) -> tuple[float, float, float, float]:
    """Mean predicted relative std of the effects with (a)'s second run, with the best found for the
    effects alone and with that run identified with the base parameters as bench/loop.py does, and the
    wall time [s]; with ``coefficients`` each coefficient's std with (a)'s second run and with the best
    found printed first."""
    begin = time.perf_counter()
    blind, _, model, truth = simulated_robot(config, seed)
    alpha1, blind_second = blind_runs(blind, seed)
    _, sigma = noise_levels(model, truth)
    b = model.base.count
    runs = [measured(model, alpha, truth) for alpha in (alpha1, blind_second)]
    blind_std = predicted_std(runs, sigma)[b:] / np.abs(truth[b:])
    with threadpool_limits(1):  # the local searches' paths are chaotic: the same rounding with any BLAS threads
        best, second = best_second_run(model, [alpha1, blind_second], sigma, np.abs(truth[b:]), seed, starts)
    with_base = predicted_std([runs[0], measured(model, second, truth)], sigma)[b:] / np.abs(truth[b:])
    for name, before, after in zip(model.effects.names, blind_std, best) if coefficients else ():
        print(f"    {name}: {before:.3%} / {after:.3%}")
    means = (float(np.mean(blind_std)), float(np.mean(best)), float(np.mean(with_base)))
    return *means, time.perf_counter() - begin


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=list(ROBOTS))
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--starts", type=int, default=STARTS, help="random starts per group")
    parser.add_argument("--coefficients", action="store_true", help="each coefficient's std, blind / best found")
    args = parser.parse_args()
    lines = []
    for robot in args.robots:
        results = []
        for seed in args.seeds:
            *means, wall = headroom(ROBOTS[robot], seed, args.starts, args.coefficients)
            results.append(means)
            print(
                f"  {robot} seed {seed}: effects std blind {means[0]:.3%}, best found {means[1]:.3%}, "
                f"identified with the base parameters {means[2]:.3%}, {wall:.0f} s",
                flush=True,
            )
        blind_std, best, with_base = np.mean(results, axis=0)
        lines.append(
            f"headroom {robot}: effects std blind {blind_std:.3%}, best second run for the effects alone "
            f"{best:.3%} ({1.0 - best / blind_std:.0%} lower), identified with the base parameters "
            f"{with_base:.3%} ({1.0 - with_base / blind_std:.0%} lower)"
        )
    print("\n".join(lines))


if __name__ == "__main__":
    main()
