"""Benchmark on the G1 arms problem: analytic gradient vs one-sided finite differences (same run),
and the wall time of a full `excite optimize configs/g1_arms.yaml`.

Run: `make bench` (or `.venv/bin/python bench/bench_g1_arms.py [CONFIG]`). Prints figures; asserts nothing.
The optimize result is kept in results/bench_<config>.h5.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import check_gradient

ROOT = Path(__file__).resolve().parent.parent


def main(config: Path) -> None:
    problem = load_problem(config)
    problem.optimizer.objective = "cond"
    excitation = build_excitation(problem)
    alpha = excitation.limits.random_start(excitation.trajectory.n_coefficients, np.random.default_rng(0), 0.7)
    check = check_gradient(excitation.criterion(), alpha, repeats=20)
    print(f"config                         {config}")
    print(f"Fourier coefficients           {check.variables}")
    print(f"analytic gradient              {check.analytic_s * 1e3:.1f} ms")
    print(f"one-sided finite differences   {check.forward_s * 1e3:.0f} ms")
    print(f"speed-up                       {check.speedup:.0f}x")
    print(f"relative error (central FD)    {check.error_central:.1e}")
    print(f"relative error (one-sided FD)  {check.error_forward:.1e}")
    target = ROOT / "results" / f"bench_{config.stem}.h5"
    start = time.perf_counter()
    run = subprocess.run(
        [sys.executable, "-m", "excite_cli", "optimize", str(config), "-o", str(target)],
        check=True,
        capture_output=True,
        text=True,
    )
    print(f"full optimize wall time        {time.perf_counter() - start:.1f} s  ({target})")
    print(run.stdout)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "configs" / "g1_arms.yaml")
