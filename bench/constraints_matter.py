"""Do the balance and self-collision constraints matter? Optimizes iteration 1 of a problem with and
without its `constraints` section and checks both results against the constrained problem's CoM
region and capsules on the fine grid.

Run: `.venv/bin/python bench/constraints_matter.py [CONFIG]` (default configs/g1_arms.yaml). Prints figures.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import copy
import sys
from pathlib import Path

import numpy as np

from excite_cli.config import ConstraintsConfig
from excite_cli.config_file import load_problem
from excite_cli.design.criterion import condition_number
from excite_cli.design.resolve import build_excitation
from excite_cli.search.sequence import run_sequence

ROOT = Path(__file__).resolve().parent.parent


def main(config: Path) -> None:
    problem = load_problem(config)
    constrained = build_excitation(problem)
    free_problem = copy.deepcopy(problem)
    free_problem.constraints = ConstraintsConfig()
    free = build_excitation(free_problem)
    print(
        f"{'constraints':<12} {'cond':>7} {'CoM excursion [cm]':>19} {'smallest capsule distance [cm] (pair)':>40} {'time [s]':>9}"
    )
    for label, excitation in (("off", free), ("on", constrained)):
        result = run_sequence(excitation, 1, problem.optimizer.seed)[0]
        checks = {
            k: v
            for c in constrained.constraints
            for k, v in c.check(result.alpha, constrained.fine_basis).details.items()
        }
        cond = condition_number(result.regressor)
        print(
            f"{label:<12} {cond:7.1f} {100 * checks.get('com_max_excursion_m', np.nan):19.2f} "
            f"{100 * checks.get('min_capsule_distance_m', np.nan):10.2f} ({checks.get('min_capsule_pair', '-')})"
            f"{result.wall_time_s:9.0f}"
        )
    region = next(c for c in constrained.constraints if c.name == "com_region")
    print(
        f"CoM region radius {100 * region.radius:.1f} cm; capsule margin "
        f"{100 * next(c for c in constrained.constraints if c.name == 'self_collision').margin:.1f} cm"
    )


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "configs" / "g1_arms.yaml")
