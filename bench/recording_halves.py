"""Is one recording's reported spread the spread between its halves? Each half of a recording is fitted
on its own, as identify fits one recording (least squares, the declared Coulomb and viscous friction, no
search); over many recordings, per base parameter, the RMS of a form's standard deviation of the
difference of the halves' estimates (each half's std combined) against the RMS of that difference:

- sandwich: the noise's, from the residuals' spectra (excite_cli/identification/fitting/noise.py);
- time blocks: CR2 over the time blocks of the cross-validation's folds (6 by default), what identify
  reports beside it for fewer than 3 trajectories (excite_cli/identification/fitting/model_error.py).

Simulated: bench/model_error.py's Panda (excite's rigid-body regressor, Coulomb 0.8 N·m and viscous
0.3 N·m·s/rad on every joint, 0.05 N·m noise) recorded for 20 s at 50 Hz on a random 10-harmonic motion
of period 20 s (the halves see different motion), with an error the model lacks: a spring and a
quadratic term on joint 2 (``spring``), friction growing as q̇|q̇| (``shape``), or a slow random walk
of the torque (``drift``); ``--periodic``: a motion of period 10 s, so the halves repeat one motion.
Real: the public Panda recording (Gaz et al. 2019, ../shared/data/panda-gaz2019: 21 s at 1 kHz, a
13.4 s period), halves [0, 10.4] and [10.6, 21] s, each fitted by identify (the other half validating):
one recording, so the median over the parameters of |difference| / (its std) / 0.674 (the median of
|z| for a standard normal).

Run: `.venv/bin/python bench/recording_halves.py [--sets 30] [--periodic]`. Prints the median ratio
and the share of base parameters within 0.7–1.4 per error and form; asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml
from model_error import NOISE, SPRING, panda

from excite_cli.config_file import load_problem
from excite_cli.identification.choice.crossval import fold_assignment
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import least_squares
from excite_cli.identification.fitting.model_error import between_time_blocks
from excite_cli.identification.fitting.noise import middle
from excite_cli.identification.fitting.normal import NormalEquations
from excite_cli.identification.pipeline import run_identification

ROOT = Path(__file__).resolve().parent.parent
REAL = ROOT.parent / "shared" / "data" / "panda-gaz2019" / "exciting_traj_1.csv"
#: Sample rate [Hz], recording length [s], harmonics per 10 s of period, identify's default folds.
RATE, LENGTH, HARMONICS, FOLDS = 50.0, 20.0, 5, 6
ERRORS = ("spring", "shape", "drift")


def recording(robot, base, rng: np.random.Generator, error: str, period: float):
    """Instants (N,) [s], base regressor rows (N·n, b), torques (N, n) and q̇ (N, n) of one recording."""
    n, count = robot.n_joints, int(HARMONICS * period / 10.0)
    t = np.arange(int(LENGTH * RATE)) / RATE
    k = np.arange(1, count + 1)
    w = 2 * np.pi / period * k
    a, b = rng.normal(0, 0.12, (2, n, count)) / np.sqrt(k) / np.sqrt(count / HARMONICS)
    s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
    q, qd, qdd = s @ a.T + c @ b.T, (c * w) @ a.T - (s * w) @ b.T, -(s * w**2) @ a.T - (c * w**2) @ b.T
    Y = robot.regressor_stack(q, qd, qdd)[:, base.independent]
    tau = (Y @ base.from_standard(robot.urdf_parameters())).reshape(-1, n) + 0.8 * np.tanh(qd / 0.01) + 0.3 * qd
    if error == "spring":
        tau[:, 1] += SPRING * q[:, 1] + 4.0 * q[:, 1] ** 2
    elif error == "shape":
        tau += 1.5 * qd * np.abs(qd)
    else:
        tau += 0.3 * np.cumsum(rng.normal(0, 0.02, tau.shape), axis=0)
    return t, Y, tau + rng.normal(0, NOISE, tau.shape), qd


def half(t, Y, tau, qd, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One half fitted as identify fits one recording: (estimates, sandwich std, time blocks' std)."""
    n = tau.shape[1]
    terms = [Term(e, j) for e in ("coulomb", "viscous") for j in range(n)]
    blocks = {Term("coulomb", j): np.tanh(qd[rows, j : j + 1] / 0.01) for j in range(n)}
    blocks.update({Term("viscous", j): qd[rows, j : j + 1] for j in range(n)})
    Yr = Y.reshape(t.size, n, -1)[rows].reshape(rows.size * n, -1)
    data = Dataset(Yr, tau[rows].ravel(), t[rows], np.zeros(rows.size, dtype=int), blocks)
    normal = NormalEquations(data, terms)
    fit = least_squares(normal, terms, middle=middle(data, least_squares(normal, terms).x, terms, None, RATE))
    block, _ = fold_assignment(data.time, data.run, FOLDS, 0.0)
    return fit.x, fit.std, np.sqrt(between_time_blocks(data, fit.x, terms, None, block, np.zeros(1, dtype=int))[0])


def simulated(sets: int, periodic: bool) -> None:
    robot, base = panda()
    b = base.count
    period = LENGTH / 2 if periodic else LENGTH
    for error in ERRORS:
        rng = np.random.default_rng(0)
        pairs = []
        for _ in range(sets):
            t, Y, tau, qd = recording(robot, base, rng, error, period)
            pairs.append([half(t, Y, tau, qd, rows) for rows in np.array_split(np.arange(t.size), 2)])
        spread = np.sqrt(np.mean([(p[0][0] - p[1][0])[:b] ** 2 for p in pairs], axis=0))
        line = []
        for k, name in ((1, "sandwich"), (2, "time blocks")):
            std = np.sqrt(np.mean([(p[0][k] ** 2 + p[1][k] ** 2)[:b] for p in pairs], axis=0))
            ratio = std / spread
            line.append(f"{name} {np.median(ratio):.2f} ({np.mean((ratio > 0.7) & (ratio < 1.4)):.0%})")
        print(f"{error:<7} {'periodic' if periodic else 'aperiodic'}: " + ", ".join(line), flush=True)


def real(folder: Path, method: str) -> None:
    """The public Panda recording's halves, each identified (friction declared, nothing searched)."""
    config = yaml.safe_load((ROOT / "configs" / "panda_identify.yaml").read_text())
    config["data"].pop("validation_blocks")
    fits = []
    for name, fit, validation in (("first", (0.0, 10.4), (10.6, 21.0)), ("second", (10.6, 21.0), (0.0, 10.4))):
        config["data"]["runs"] = [
            {"file": str(REAL), "role": "fit", "crop": list(fit)},
            {"file": str(REAL), "role": "validation", "crop": list(validation)},
        ]
        config["identification"] = {
            "method": method,
            "declared_effects": {"*": ["coulomb", "viscous"]},
            "candidates": [],
            "fit": "least_squares",
        }
        config["output"] = str(folder / f"{name}.h5")
        (folder / f"{name}.yaml").write_text(yaml.safe_dump(config))
        fits.append(run_identification(load_problem(folder / f"{name}.yaml", IdentifyProblem))[0].selection.fit)
    d = fits[0].x - fits[1].x
    line = []
    for name, first, second in (("sandwich", fits[0].std, fits[1].std), ("time blocks", *(f.between for f in fits))):
        z = np.abs(d) / np.sqrt(first**2 + second**2)
        z = z[np.isfinite(z)]
        line.append(f"{name} {0.6745 / np.median(z):.2f} ({np.mean(z > 3):.0%} beyond 3 std)")
    print(f"real Panda, {method}, {z.size} coefficients: " + ", ".join(line), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", type=int, default=30)
    parser.add_argument("--periodic", action="store_true")
    args = parser.parse_args()
    print(f"{args.sets} recordings per error; std over the spread between halves: median (share in 0.7–1.4)")
    simulated(args.sets, args.periodic)
    if not REAL.exists():
        print(f"(real Panda skipped: {REAL} not found)", file=sys.stderr)
        return
    with tempfile.TemporaryDirectory() as tmp:
        for method in ("ls", "wls"):
            real(Path(tmp), method)


if __name__ == "__main__":
    main()
