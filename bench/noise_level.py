"""Does identify measure the noise it was given? The smoke Panda trajectories (a result of
``excite optimize configs/smoke.yaml``) simulated by ``excite simulate`` with Coulomb 0.6 N·m and viscous
0.4 N·m·s/rad on every joint, 500 Hz, 4 periods, 0.2 mrad of encoder noise and one of two torque
noises: *absolute* 0.05 N·m (a torque sensor's), *relative* 2 % of the torque over a 0.005 N·m floor
(a motor current's). Identified with that friction declared and no search (run 1 fitted, run 2
validation), least squares; the noise table of the report (:mod:`excite_cli.identification.fitting.noise_level`).

Printed per truth and seed: the fitted ρ per joint, their median over the truth's ρ, and the joints
whose preferred kind is the truth's (a letter per joint: a absolute, r relative) and, under relative
noise, how far each joint's relative part at its RMS torque rises above the floor; then per truth the seeds whose median ρ is within 20 % (relative)
and the seeds where the truth's kind is preferred on at least 6 of the 7 joints.

    .venv/bin/python bench/noise_level.py [RESULT.h5] [--seeds 0 1 ...]

Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import tempfile
from pathlib import Path

import numpy as np
import yaml

from excite_cli.config_file import load_problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.workflows.simulate import simulate_runs

ROOT = Path(__file__).resolve().parent.parent
TRUTHS = {"absolute": (0.05, 0.0), "relative": (0.005, 0.02)}  # (torque_noise [N·m], torque_noise_relative)


def measured(result: Path, truth: str, seed: int, folder: Path) -> list:
    """The noise levels identify fits to the two runs of ``result`` simulated under ``truth``, and each
    joint's RMS torque on the validation run [N·m]."""
    sigma, rho = TRUTHS[truth]
    effects = {"sample_rate": 500.0, "periods": 4, "position_noise": 0.0002, "torque_noise": sigma}
    effects |= {"torque_noise_relative": rho, "seed": seed, "effects": {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}}}
    runs = simulate_runs(result, SimulationConfig.model_validate(effects), folder / "runs")
    config = yaml.safe_load((ROOT / "configs" / "panda_identify_simulated.yaml").read_text())
    config["data"]["runs"] = [{"file": str(runs[0]), "role": "fit"}, {"file": str(runs[1]), "role": "validation"}]
    config["identification"] |= {
        "declared_effects": {"*": ["coulomb", "viscous"]},
        "candidates": [],
        "fit": "least_squares",
    }
    (folder / "identify.yaml").write_text(yaml.safe_dump(config))
    report = run_identification(load_problem(folder / "identify.yaml", IdentifyProblem))[0]
    return report.noise_levels, report.rms_torque


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("result", type=Path, nargs="?", default=ROOT / "results" / "smoke.h5")
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    args = parser.parse_args()
    for truth, (_, rho) in TRUTHS.items():
        within, preferred = 0, 0
        for seed in args.seeds:
            with tempfile.TemporaryDirectory() as tmp:
                levels, rms = measured(args.result, truth, seed, Path(tmp))
            fitted = np.array([level.relative for level in levels])
            right = sum(level.preferred == truth for level in levels)
            ratio = float(np.median(fitted) / rho) if rho else float("nan")
            within += bool(rho) and abs(ratio - 1) <= 0.2
            preferred += right >= 6
            print(
                f"{truth} seed {seed}: rho [%] {' '.join(f'{100 * x:.2f}' for x in fitted)}; median / truth "
                f"{ratio:.3f}; the truth's kind preferred on {right} of {len(levels)} joints "
                f"({''.join(level.preferred[0] for level in levels)}); rho x RMS torque / floor "
                f"{' '.join(f'{rho * r / TRUTHS[truth][0]:.2g}' for r in rms) if rho else '-'}",
                flush=True,
            )
        print(
            f"{truth}: median rho within 20 % in {within if rho else '-'} of {len(args.seeds)} seeds; the truth's kind "
            f"preferred on at least 6 of 7 joints in {preferred} of {len(args.seeds)}",
            flush=True,
        )


if __name__ == "__main__":
    main()
