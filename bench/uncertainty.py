"""Are the standard deviations `excite identify` reports the spread a user would see? A simulated Panda
(the smoke trajectories, 3 runs, Coulomb 0.6 Nm and viscous 0.4 Nm·s/rad on every joint, 0.05 Nm
torque noise, encoder noise 2e-4 rad) drawn again with ``--draws`` noise seeds; each draw identified
with the true model declared and nothing searched (the model is the same in every draw), runs 1 and
2 fitted, by least squares and by the reported fit's weighted least squares.

Printed per fit: for every base parameter and effect coefficient the ratio of its mean reported
standard deviation (the sandwich of excite_cli/identification/fitting/noise.py) to the standard
deviation of its estimates over the draws; the share of ratios within 0.8–1.25, their quartiles and
extremes, and the share a perfect standard deviation would have by chance: the spread of d draws is
itself uncertain (χ² with d − 1 degrees of freedom; with 20 draws ±16 %), so even the true standard
deviation falls outside 0.8–1.25 for about 17 % of the parameters.

    .venv/bin/python bench/uncertainty.py [--draws 20]
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import tempfile
from pathlib import Path

import numpy as np
import yaml
from identify_transfer import COLUMNS, PANDA, PANDA_ROBOT, optimized, panda_runs
from scipy.stats import chi2

from excite_cli.config_file import load_problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.pipeline import run_identification

ROOT = Path(__file__).resolve().parent.parent
EFFECTS = {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}}


def identified(folder: Path, runs: Path, method: str) -> tuple[np.ndarray, np.ndarray]:
    """(estimates, reported standard deviations) of the base parameters and effects, both (b + k,)."""
    config = {
        "robot": PANDA_ROBOT,
        "data": {
            "runs": [{"file": str(runs / f"run_{k}.csv"), "role": "fit"} for k in (1, 2)]
            + [{"file": str(runs / "run_3.csv"), "role": "validation"}],
            "columns": COLUMNS,
        },
        "identification": {
            "method": method,
            "declared_effects": {"*": ["coulomb", "viscous"]},
            "candidates": [],
            "fit": "least_squares",
        },
        "output": str(folder / "report.h5"),
    }
    (folder / "identify.yaml").write_text(yaml.safe_dump(config))
    report = run_identification(load_problem(folder / "identify.yaml", IdentifyProblem))[0]
    return report.selection.fit.x, report.selection.fit.std


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--draws", type=int, default=20)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        smoke = folder / "smoke.yaml"
        config = yaml.safe_load((ROOT / "configs" / "smoke.yaml").read_text())
        config.update(sequence={"iterations": 3}, output=str(folder / "smoke.h5"))
        smoke.write_text(yaml.safe_dump(config))
        trajectory = optimized(folder, smoke, "smoke")
        for method in ("ls", "wls"):
            estimates, stds = [], []
            for draw in range(args.draws):
                runs = panda_runs(folder, trajectory, f"{method}_{draw}", EFFECTS, seed=draw, periods=2)
                x, std = identified(folder, runs, method)
                estimates.append(x)
                stds.append(std)
            spread = np.std(estimates, axis=0, ddof=1)
            ratio = np.mean(stds, axis=0) / spread
            inside = np.mean((ratio >= 0.8) & (ratio <= 1.25))
            quartiles = " ".join(f"{v:.2f}" for v in np.quantile(ratio, [0.25, 0.5, 0.75]))
            dof = args.draws - 1  # spread / std ∈ [0.8, 1.25] ⇔ χ²_dof / dof ∈ [0.64, 1.5625]
            chance = chi2.cdf(1.5625 * dof, dof) - chi2.cdf(0.64 * dof, dof)
            print(
                f"uncertainty {method} ({len(PANDA)} joints, {ratio.size} parameters, {args.draws} draws): reported "
                f"std / spread within 0.8-1.25 for {100 * inside:.0f} % (a perfect std: {100 * chance:.0f} %), "
                f"quartiles {quartiles}, range {ratio.min():.2f}-{ratio.max():.2f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
