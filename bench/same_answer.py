"""One problem, one answer: `excite optimize` run four ways on this machine, as a user runs it.

Iteration 1 (default) of a config, its seed, run
- as the Makefile runs it (the BLAS library's default threads, a local pool of one process per core),
- with ``OPENBLAS_NUM_THREADS=1``,
- with ``--workers 1`` (every restart in the main process),
- on a real Dask cluster (``dask scheduler`` and one ``dask worker`` process started here),
and for each the digest of the stored base parameters (names and regrouping matrix K), cond(C) and
cond(CL) after the iterations, and the kept restart's end value. The kernels the runs compute with
(:func:`excite_cli.kernels.describe`) are printed first: other kernels round otherwise.

    .venv/bin/python bench/same_answer.py [CONFIG] [--iterations K]
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import hashlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py

from excite_cli.kernels import describe

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent


def figures(path: Path) -> tuple[str, str, str, str]:
    """Digest of the stored base, cond(C) and cond(CL) after the last iteration, the kept end value."""
    with h5py.File(path) as f:
        names = "|".join(s.decode() for s in f["robot/base_parameter_names"][()])
        digest = hashlib.sha256(names.encode() + f["robot/regrouping_matrix"][()].tobytes()).hexdigest()[:12]
        table = f["table"][()]
        last = f["iterations"][str(table["iteration"][-1])]["restarts"]
        kept = last[str(last.attrs["kept"])].attrs["objective"]
    return digest, f"{table['cond_stacked'][-1]:.6g}", f"{table['scaled_cond_stacked'][-1]:.6g}", f"{kept:.8g}"


def run(config: Path, iterations: int, out: Path, env: dict, extra: list[str]) -> tuple:
    argv = [str(BIN / "excite"), "optimize", str(config), "--iterations", str(iterations), "-o", str(out), "--force"]
    begin = time.perf_counter()
    subprocess.run(argv + extra, check=True, env=env, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return (*figures(out), f"{time.perf_counter() - begin:.0f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("config", type=Path, nargs="?", default=ROOT / "configs" / "g1_arms.yaml")
    parser.add_argument("--iterations", type=int, default=1)
    args = parser.parse_args()
    print("kernels:", describe())
    base = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    print(f"{'run':<28} {'base digest':>13} {'cond(C)':>10} {'cond(CL)':>10} {'kept end value':>16} {'wall [s]':>9}")
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        ways = [
            ("default", base, []),
            ("OPENBLAS_NUM_THREADS=1", {**base, "OPENBLAS_NUM_THREADS": "1"}, []),
            ("--workers 1", base, ["--workers", "1"]),
        ]
        for name, env, extra in ways:
            print(
                f"{name:<28} "
                + " ".join(f"{x:>12}" for x in run(args.config, args.iterations, tmp / "r.h5", env, extra)),
                flush=True,
            )
        port = 8700 + os.getpid() % 200
        scheduler = subprocess.Popen(
            [str(BIN / "dask"), "scheduler", "--port", str(port), "--no-dashboard"], stderr=subprocess.DEVNULL
        )
        worker = subprocess.Popen(
            [
                str(BIN / "dask"),
                "worker",
                f"tcp://127.0.0.1:{port}",
                "--nworkers",
                "2",
                "--nthreads",
                "1",
                "--no-dashboard",
            ],
            stderr=subprocess.DEVNULL,
        )
        try:
            time.sleep(8)
            row = run(args.config, args.iterations, tmp / "r.h5", base, ["--scheduler", f"tcp://127.0.0.1:{port}"])
            print(f"{'dask worker (2 processes)':<28} " + " ".join(f"{x:>12}" for x in row), flush=True)
        finally:
            for process in (worker, scheduler):
                process.terminate()
                process.wait(10)


if __name__ == "__main__":
    main()
