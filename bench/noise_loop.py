"""The noise loop: after one recording, is the next design as good as one made knowing the noise?

For each robot (a config), optimizer seed and true noise (bench/criteria.py's: *absolute* 2 % of each
joint's RMS torque on an unseen motion, a torque sensor's; *relative* 2 % of the torque over a floor of
0.2 % of that RMS, a motor current's):

Every design is one trajectory of the config's problem under A-optimality in the URDF-scaled frame
(``log_trace_inverse``, ``urdf``: the default, as bench/criteria.py's table), its restarts and screening.

1. the first trajectory, designed as the config says (its ``noise`` section; where it has none, the
   hedge, :func:`~excite_cli.design.noise.hedged_noise`);
2. its recording: sampled at 100 Hz over its duration, torques from RNEA with the URDF's inertias plus
   one draw of the true noise (noise seed = optimizer seed);
3. identified as identify does with nothing declared: weighted least squares of the base parameters
   (each joint's rows by the inverse of its residual under least squares, Gautier 1997), then each
   joint's noise σ² = a² + (ρτ)² fitted to the residual against the predicted torque, measured again
   after the reweighted fits where some joint's noise grows with the torque
   (:func:`~excite_cli.identification.fitting.noise_level.measured_noise`, no filter: gain 1; the
   wrench rows keep their weight) and its RMS residual σ_j;
4. the second trajectory, the recording as prior data (``sequence.prior``: each row scaled to the cost
   grid's rate), designed three ways from the same random starts:
   *measured*, as ``optimize --prior REPORT`` designs it: the recording's rows and the new ones weighed by
   the fitted noise at their predicted torque, a taken at its 95 % upper bound
   (:class:`~excite_cli.stored.design_model.MeasuredPrior`);
   *σ_j only*, a report without a noise table (every row of a joint weighs the same, σ̄/σ_j);
   *told the truth*, every row, the recording's and the new, weighed by the true noise (the config's
   ``noise: {absolute: s_j, relative: ρ}``).
   A floating base's 6 wrench rows (the G1's) weigh σ̄ in all three, as a design weighs them (no joint's
   sensor measures them and a config cannot declare their noise); their true noise enters the error.

Printed per robot, truth and seed: the fitted ρ per joint (median over the joints), the kinds the data
prefer, and each second design's expected parameter error: the RMS over the b identifiable directions of
the error of weighted least squares on both recordings under the true noise, in the URDF-scaled frame
(bench/criteria.py's "predicted"), with its ratio to the told-the-truth design's. The last line per robot:
the largest ratio of *measured* (and of *σ_j only*) over its truths and seeds.

    .venv/bin/python bench/noise_loop.py CONFIG [CONFIG ...] [--seeds 0 1 2] [--truths absolute relative]
        [--starts K]

``--starts K``: each second design from K optimizer starts (seeds seed + 1000, + 2000, ...): a line per
start, and the ratios of the mean expected errors over the starts (the designs of one noise model
differ between starts by as much as the noise models do on the G1).

Runs in one BLAS thread whatever ``OPENBLAS_NUM_THREADS`` says: its own least squares round by the
threads, and the second design follows them.

Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np
from criteria import RATE, noise_scale, samples
from threadpoolctl import threadpool_limits

from excite_cli.config import NoiseConfig
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.identification.fitting.noise_level import measured_noise
from excite_cli.search.engine import Engine, default_workers
from excite_cli.search.sequence import run_sequence
from excite_cli.stored.design_model import MeasuredPrior

CRITERION = ("log_trace_inverse", "urdf")  # A-optimality in the URDF-scaled frame, as bench/criteria.py's table
DESIGNS = ("measured", "sigma only", "told the truth")


def designed(excitation, prior: np.ndarray, seed: int) -> np.ndarray:
    """The Fourier coefficients of one trajectory designed for ``excitation`` with C₀ = ``prior``."""
    workers = min(default_workers(), excitation.spec.optimizer.screened or excitation.spec.optimizer.restarts)
    with Engine(excitation, workers) as engine:
        return run_sequence(excitation, 1, seed, prior=prior, engine=engine)[0].alpha


def recorded(excitation, alpha: np.ndarray, noise: tuple, seed: int) -> tuple:
    """The recording of α under the true ``noise`` (absolute (n_rows,), ρ: bench/criteria.noise_scale):
    base regressor Y (T·n_rows, b), true torques (T, n_rows), their true noise σ (T, n_rows) and one draw
    of the measured torques (T, n_rows)."""
    Y, tau = samples(excitation, alpha)
    absolute, rho = noise
    sigma = np.sqrt(absolute**2 + (rho * tau) ** 2)
    return Y, tau, sigma, tau + np.random.default_rng(seed).normal(0.0, 1.0, tau.shape) * sigma


def identified(Y: np.ndarray, measured: np.ndarray, n: int) -> tuple[np.ndarray, list, np.ndarray]:
    """Weighted least squares of the recording as identify's default (Gautier 1997: each joint's rows
    by 1/σ_j, σ_j its residual under ordinary least squares), then the joints' (the last ``n`` rows of
    each instant) RMS residual σ_j (n,) [Nm], fitted noise levels and predicted torques (T, n) [Nm]."""
    rows = measured.shape[1]
    plain = measured - (Y @ np.linalg.lstsq(Y, measured.ravel(), rcond=None)[0]).reshape(measured.shape)
    weights = np.tile(1.0 / np.sqrt((plain**2).mean(axis=0)), len(measured))

    def fit(w: np.ndarray) -> np.ndarray:
        beta = np.linalg.lstsq(Y * w[:, None], measured.ravel() * w, rcond=None)[0]
        return (Y @ beta).reshape(-1, rows)[:, -n:]

    def refit(joints: np.ndarray) -> np.ndarray:  # the joints' rows by the noise measured, the wrench's as before
        w = weights.reshape(-1, rows).copy()
        w[:, -n:] = joints
        return fit(w.ravel())

    predicted = fit(weights)
    levels = measured_noise(measured[:, -n:], predicted, np.ones(len(predicted)), np.ones(n, dtype=bool), refit)
    return np.sqrt(((measured[:, -n:] - predicted) ** 2).mean(axis=0)), levels, predicted


def second_designs(problem, excitation, record: tuple, fitted: tuple, noise: tuple, seed: int):
    """The second trajectory designed ``measured``, ``sigma only`` and ``told the truth`` (module docstring)."""
    Y, tau, sigma, _ = record
    rms, levels, predicted = fitted
    n, rows = excitation.robot.n_joints, excitation.robot.n_rows
    out = {}
    level = np.array([[x.absolute, x.relative, x.absolute_upper] for x in levels])
    for name, lab in (("measured", level), ("sigma only", None)):
        measured = MeasuredPrior(list(excitation.robot.joint_names), rms, RATE, lab)
        scale = measured.time_scale(problem.trajectory.cost_period)
        weights = np.ones((len(tau), rows))  # a floating base's wrench rows weigh σ̄
        weights[:, -n:] = measured.row_weights(predicted.ravel()).reshape(-1, n)  # as stored.prior weighs a report's
        prior = Y * (weights.ravel() * scale)[:, None]
        spec = replace(excitation.spec, measured=measured)  # as resolve makes it: a measured prior, no hedge
        spec = replace(spec, noise=None, hedged=False) if spec.hedged else spec
        out[name] = designed(replace(excitation, spec=spec), prior, seed)
    absolute, rho = noise
    joints = problem.robot.active_joints
    told = problem.model_copy(deep=True)
    told.noise = NoiseConfig(absolute=dict(zip(joints, absolute[-n:].tolist())), relative=rho)
    truth = build_excitation(told)
    weights = truth.noise.scale / sigma  # (T, n_rows)
    weights[:, : rows - n] = 1.0  # a floating base's wrench rows weigh σ̄, as the design weighs them
    out["told the truth"] = designed(truth, Y * (weights.ravel() * scale)[:, None], seed)
    return out


def expected_error(excitation, record: tuple, alpha: np.ndarray, noise: tuple) -> float:
    """RMS over the identifiable directions of the scaled parameter error of weighted least squares on
    the recording and α's (sampled as the recording), under the true noise (bench/criteria.py's
    "predicted")."""
    Y1, _, sigma1, _ = record
    Y2, tau2 = samples(excitation, alpha)
    absolute, rho = noise
    sigma2 = np.sqrt(absolute**2 + (rho * tau2) ** 2)
    weighted = np.vstack([Y1 / sigma1.ravel()[:, None], Y2 / sigma2.ravel()[:, None]])
    inverse_frame = np.linalg.inv(excitation.scaled_frame)
    covariance = inverse_frame @ np.linalg.inv(weighted.T @ weighted) @ inverse_frame.T
    return float(np.sqrt(np.trace(covariance) / covariance.shape[0]))


def report(config: Path, excitation, record: tuple, noise: tuple, truth: str, seed: int, starts: int, problem) -> dict:
    """Identify the recording (made under the true ``noise``), design the second trajectory three ways from
    each of ``starts`` optimizer starts (seeds seed + 1000, + 2000, ...), print a line per start; each
    design's mean expected error over the starts."""
    n = excitation.robot.n_joints
    fitted = identified(record[0], record[3], n)
    levels = fitted[1]
    rho = np.array([x.relative for x in levels])
    head = (
        f"{config.stem} {truth} seed {seed}: rho [%] {' '.join(f'{100 * x:.2f}' for x in rho)} (median "
        f"{100 * np.median(rho):.2f}); preferred {''.join(x.preferred[0] for x in levels)}"
    )
    errors = {name: [] for name in DESIGNS}
    for start in range(starts):
        second = second_designs(problem, excitation, record, fitted, noise, seed + 1000 * (start + 1))
        e = {name: expected_error(excitation, record, a, noise) for name, a in second.items()}
        for name in DESIGNS:
            errors[name].append(e[name])
        print(
            f"{head}; start {start + 1}: expected error "
            + ", ".join(f"{name} {100 * x:.4g} % ({x / e['told the truth']:.3f})" for name, x in e.items()),
            flush=True,
        )
    return {name: float(np.mean(x)) for name, x in errors.items()}


def main() -> None:
    # one BLAS thread for the bench's own least squares too (a design runs in one already): their last bits
    # follow the threads, and the second design's optimizer path follows them (the G1's cells moved by 1-2 %)
    threadpool_limits(limits=1)
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("configs", type=Path, nargs="+")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--truths", nargs="+", default=["absolute", "relative"])
    parser.add_argument("--starts", type=int, default=1, help="optimizer starts of each second design")
    args = parser.parse_args()
    for config in args.configs:
        problem = load_problem(config)
        problem.optimizer.objective, problem.optimizer.scaling = CRITERION
        excitation = build_excitation(problem)
        ratios = {name: [] for name in DESIGNS[:2]}
        noises = {truth: noise_scale(excitation, truth == "relative") for truth in args.truths}
        for seed in args.seeds:
            problem.optimizer.seed = seed
            first = designed(excitation, None, seed)
            for truth in args.truths:
                record = recorded(excitation, first, noises[truth], seed)
                mean = report(config, excitation, record, noises[truth], truth, seed, args.starts, problem)
                for name in ratios:
                    ratios[name].append(mean[name] / mean["told the truth"])
                if args.starts > 1:
                    print(
                        f"{config.stem} {truth} seed {seed}: mean over {args.starts} starts, / told the truth: "
                        + ", ".join(f"{name} {r[-1]:.3f}" for name, r in ratios.items()),
                        flush=True,
                    )
        print(
            f"loop {config.stem}: second design / told the truth (mean over starts), largest over truths and "
            "seeds: " + ", ".join(f"{name} {max(r):.3f}" for name, r in ratios.items()),
            flush=True,
        )


if __name__ == "__main__":
    main()
