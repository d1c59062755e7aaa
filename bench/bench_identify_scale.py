"""Peak memory and wall time of `excite identify` on long runs, as labs record them (1 kHz for tens of
minutes): a simulated Panda run of N rows (a Fourier excitation, RNEA torques of the URDF, Coulomb
friction, noise) written as CSV and as NPZ, identified in a child process whose peak resident memory
is read from the OS. Usage: python bench/bench_identify_scale.py [ROWS ...] (default 500000 2000000).
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from excite_cli.config_file import load_problem
from excite_cli.dynamics.robot import load_robot

ROOT = Path(__file__).resolve().parent.parent
JOINTS = [f"panda_joint{k}" for k in range(1, 8)]


def simulated_run(rows: int, rate: float = 1000.0) -> dict[str, np.ndarray]:
    """time (rows,), q and tau (rows, 7) of a slow multi-sine excitation of the Panda."""
    robot = load_robot(load_problem(ROOT / "configs" / "panda_joint_limits.yaml").robot)
    t = np.arange(rows) / rate
    rng = np.random.default_rng(0)
    w = 2 * np.pi * np.array([0.1, 0.23, 0.37])
    amp = rng.uniform(0.1, 0.3, (7, 3))
    q = np.sin(np.outer(t, w)) @ amp.T
    qd = (np.cos(np.outer(t, w)) * w) @ amp.T
    qdd = -(np.sin(np.outer(t, w)) * w**2) @ amp.T
    tau = (
        np.array([robot.torques(*x) for x in zip(q, qd, qdd)]) + 0.3 * np.tanh(qd / 0.01) + rng.normal(0, 0.05, q.shape)
    )
    return {"time": t, "q": q, "tau": tau}


def identify(folder: Path, run_file: str, columns: dict) -> tuple[float, float]:
    """Wall time [s] and peak resident memory [GiB] of `excite identify` on one file."""
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {"runs": [{"file": run_file, "role": "blocks"}], "columns": columns},
        "output": str(folder / "ident.h5"),
    }
    path = folder / "identify.yaml"
    path.write_text(yaml.safe_dump(config))
    # the app returns its exit status (standalone_mode=False): a refused or failed run must fail the bench
    child = (
        "import resource, sys\nfrom excite_cli.cli import app\ntry:\n    code = app(sys.argv[1:], standalone_mode=False)\n"
        "finally:\n    print('PEAK_KB', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr)\nsys.exit(code or 0)"
    )
    start = time.perf_counter()
    result = subprocess.run(
        [sys.executable, "-c", child, "identify", str(path), "--force"], capture_output=True, text=True
    )
    wall = time.perf_counter() - start
    peak = [line for line in result.stderr.splitlines() if line.startswith("PEAK_KB")]
    if result.returncode != 0 or not peak:
        raise SystemExit(result.stderr)
    return wall, int(peak[-1].split()[1]) / 1024**2


def main(sizes: list[int]) -> None:
    print(f"{'rows':>9} {'format':>6} {'wall [s]':>9} {'peak [GiB]':>10}")
    for rows in sizes:
        data = simulated_run(rows)
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            np.savez(folder / "run.npz", **data)
            q_cols = [f"q[{k}]" for k in range(7)]
            wall, peak = identify(
                folder, "run.npz", {"time": "time", "q": q_cols, "tau": [f"tau[{k}]" for k in range(7)]}
            )
            print(f"{rows:>9} {'npz':>6} {wall:>9.1f} {peak:>10.2f}", flush=True)
            header = ",".join(["time"] + [f"q{k}" for k in range(7)] + [f"t{k}" for k in range(7)])
            np.savetxt(
                folder / "run.csv",
                np.column_stack([data["time"], data["q"], data["tau"]]),
                delimiter=",",
                header=header,
                comments="",
                fmt="%.9g",
            )
            wall, peak = identify(
                folder, "run.csv", {"q": [f"q{k}" for k in range(7)], "tau": [f"t{k}" for k in range(7)]}
            )
            print(f"{rows:>9} {'csv':>6} {wall:>9.1f} {peak:>10.2f}", flush=True)


if __name__ == "__main__":
    main([int(x) for x in sys.argv[1:]] or [500_000, 2_000_000])
