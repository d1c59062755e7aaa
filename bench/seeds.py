"""Seed table: `excite optimize` for several seeds and BLAS thread settings, as a user runs it.

For each (seed, threads) it runs the command line in a fresh process (``OPENBLAS_NUM_THREADS`` /
``OMP_NUM_THREADS`` set to the thread count, or left unset for the library's default) and prints
cond(C) after each iteration, cond(CL) and the excitation ē of the last one (which do not depend on
the choice of base columns), the kept restart's
stop reason and KKT residual per iteration, and the wall time; then the median and the worst.

    .venv/bin/python bench/seeds.py configs/g1_arms.yaml --iterations 1 --seeds 0 1 2 3 4
    .venv/bin/python bench/seeds.py configs/panda_joint_limits.yaml --seeds 0 1 2 3 4 --threads default
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
EXCITE = Path(sys.executable).with_name("excite")


def run(config: Path, seed: int, threads: str, iterations: int | None, folder: Path) -> dict:
    """One `excite optimize` run; its figures from the result file."""
    out = folder / f"seed{seed}_{threads}.h5"
    env = {
        k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
    }
    if threads != "default":
        env.update(OPENBLAS_NUM_THREADS=threads, OMP_NUM_THREADS=threads, MKL_NUM_THREADS=threads)
    argv = [str(EXCITE), "optimize", str(config), "--seed", str(seed), "--output", str(out), "--force"]
    if iterations:
        argv += ["--iterations", str(iterations)]
    begin = time.perf_counter()
    subprocess.run(argv, check=True, env=env, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - begin
    with h5py.File(out) as f:
        table = f["table"][()]
        groups = [f["iterations"][str(k)] for k in table["iteration"]]
        kept = [g["restarts"][str(g["restarts"].attrs["kept"])].attrs for g in groups]
        return {
            "cond": list(table["cond_stacked"]),
            "scaled": float(table["scaled_cond_stacked"][-1]),
            "excitation": float(table["excitation_stacked"][-1]),
            "stop": [str(a["stop"]) for a in kept],
            "kkt": [float(a["kkt_residual"]) for a in kept],
            "max_violation": max(float(g.attrs["max_violation"]) for g in groups),
            "transitions": max(float(g.attrs.get("transition_max_violation", -np.inf)) for g in groups),
            "wall": wall,
        }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("config", type=Path)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--threads", nargs="+", default=["default", "1"])
    parser.add_argument("--iterations", type=int, default=None)
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        print(
            "| seed | BLAS threads | cond(C) after each iteration | cond(CL) | ē [Nm] | stop (kept restart) | KKT residual "
            "| max violation (grid / transitions) | wall [s] |"
        )
        print("|---|---|---|---|---|---|---|---|---|")
        for seed in args.seeds:
            for threads in args.threads:
                r = run(args.config.resolve(), seed, threads, args.iterations, Path(tmp))
                rows.append(r)
                print(
                    f"| {seed} | {threads} | {' / '.join(f'{c:.2f}' for c in r['cond'])} | {r['scaled']:.0f} | {r['excitation']:.4g} | "
                    f"{'; '.join(r['stop'])} | {' / '.join(f'{k:.1e}' for k in r['kkt'])} | "
                    f"{r['max_violation']:+.1e} / {r['transitions']:+.1e} | {r['wall']:.1f} |",
                    flush=True,
                )
    last = np.array([r["cond"][-1] for r in rows])
    level = np.array([r["excitation"] for r in rows])
    walls = np.array([r["wall"] for r in rows])
    print(
        f"\nlast cond(C): median {np.median(last):.2f}, worst {last.max():.2f}, best {last.min():.2f} "
        f"(worst within {100 * (last.max() / last.min() - 1):.1f} % of the best); last ē: median {np.median(level):.4g}, "
        f"worst {level.min():.4g} (within {100 * (1 - level.min() / level.max()):.1f} % of the best); "
        f"wall: median {np.median(walls):.1f} s, worst {walls.max():.1f} s"
    )


if __name__ == "__main__":
    main()
