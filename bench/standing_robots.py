"""Legged robots excite does not ship, from their own files with no hand edit: `excite init` (its sizes fitted
to the default 5 min budget), `excite check` (its estimate), `excite optimize` (3 iterations, wall time
against the estimate), `excite export` (the held joints' feed-forward columns), then each iteration played
in MuJoCo by bench/balance.py (the URDF compiled by MuJoCo with the soles as contacts, a joint PD on the
held joints with and without the exported feed-forward, speed 1).

One block per robot:
`robot R: init I s, check estimate E s (at most A s), optimize W s (W/E), export: H held-joint torque columns`
then per iteration cond(C), ē, the ZMP margin, the kept restart's end (KKT residual), and balance.py's
summary lines per stance.

    .venv/bin/python bench/standing_robots.py [--robots g1 romeo icub b1-z1 talos] [--stances pd1000/40 ...]
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = {
    "g1": "g1_description/urdf/g1_29dof_rev_1_0.urdf",
    "romeo": "romeo_description/urdf/romeo.urdf",
    "icub": "icub_description/robots/icub.urdf",
    "b1-z1": "b1_description/urdf/b1-z1.urdf",
    "talos": "talos_data/robots/talos_reduced.urdf",
}
EXCITE = [sys.executable, "-m", "excite_cli"]


def _run(args: list[str], cwd: Path) -> tuple[float, str]:
    """Wall time [s] and output of a command; a failure other than a warning (exit 1) stops the bench."""
    start = time.perf_counter()
    done = subprocess.run(args, cwd=cwd, capture_output=True, text=True)
    if done.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(args)} failed:\n{done.stdout}\n{done.stderr}")
    return time.perf_counter() - start, done.stdout + done.stderr


def _estimate(text: str) -> tuple[float, float]:
    """check's expected and largest estimate [s], from its line."""
    found = re.search(r"estimated time: about ([\d.]+) (s|min|h), at most ([\d.]+) (s|min|h)", text)
    scale = {"s": 1.0, "min": 60.0, "h": 3600.0}
    return float(found[1]) * scale[found[2]], float(found[3]) * scale[found[4]]


def _iterations(result: Path) -> list[str]:
    """One line per iteration of the result: cond(C), ē, the ZMP margin and the kept restart's end."""
    lines = []
    with h5py.File(result) as f:
        for key in sorted(f["iterations"], key=int):
            g = f["iterations"][key]
            kept = g["restarts"][str(g["restarts"].attrs["kept"])].attrs
            lines.append(
                f"  iteration {key}: cond(C) {g.attrs['cond_stacked']:.4g}, ē {g.attrs['excitation_stacked_Nm']:.3f} N·m, "
                f"ZMP margin {1000 * g.attrs['zmp_min_margin_m']:.1f} mm, kept restart {kept['stop']} "
                f"(KKT {kept['kkt_residual']:.1e}, {kept['iterations']} iterations), {g.attrs['wall_time_s']:.0f} s"
            )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=list(ROBOTS))
    parser.add_argument("--stances", nargs="+", default=["pd1000/40", "pd1000/40+feedforward"])
    parser.add_argument("--keep", type=Path, help="keep the configs and results in this folder")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        for name in args.robots:
            config, result = folder / f"{name}.yaml", folder / f"{name}.h5"
            t_init, _ = _run([*EXCITE, "init", ROBOTS[name], "-o", str(config), "--force"], folder)
            expected, at_most = _estimate(_run([*EXCITE, "check", str(config)], folder)[1])
            t_opt, _ = _run([*EXCITE, "optimize", str(config), "-o", str(result), "--force"], folder)
            csv = folder / f"{name}.csv"
            _run([*EXCITE, "export", str(result), "--rate", "1000", "-o", str(csv), "--force"], folder)
            header = next(line for line in csv.read_text().splitlines() if not line.startswith("#"))
            with h5py.File(result) as f:
                active = len(f["robot/joint_names"]) if "robot/joint_names" in f else 0
            held = sum(column.startswith("tau_") for column in header.split(",")) - active
            print(
                f"robot {name}: init {t_init:.0f} s, check estimate {expected:.0f} s (at most {at_most:.0f} s), "
                f"optimize {t_opt:.0f} s ({t_opt / expected:.2f} of the estimate), export: {held} held-joint "
                "torque columns",
                flush=True,
            )
            print("\n".join(_iterations(result)), flush=True)
            balance = [sys.executable, str(ROOT / "bench" / "balance.py"), "--config", str(config), "--result"]
            _, text = _run([*balance, str(result), "--stances", *args.stances, "--speeds", "1", "--no-push"], folder)
            print("\n".join(f"  {line}" for line in text.splitlines() if line.startswith(("summary", "balance"))))


if __name__ == "__main__":
    main()
