"""Same behaviour as an earlier commit: the smoke run's α, the G1 run and the Panda identification
reports, bit for bit.

The earlier commit is checked out in a temporary git worktree and run with this checkout's virtual
environment (``PYTHONPATH`` puts its package first); then this checkout runs the same commands on the
same config files. Every dataset and attribute of each pair of HDF5 files is compared bit for bit,
except what records the run rather than its result (wall times, creation time, the excite version,
the config file's path).

    .venv/bin/python bench/same_behaviour.py REV [--quick]

``--quick`` leaves out the 3-iteration G1 run (about a minute each side). Prints one line per file
and every difference; exits 1 when there is one.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
RUNS = {
    "smoke.h5": ["optimize", "configs/smoke.yaml", "--force"],
    "g1.h5": ["optimize", "configs/g1_arms.yaml", "--force"],
    "panda_identify.h5": ["identify", "configs/panda_identify.yaml", "--force"],
    "panda_simulated.h5": ["identify", "configs/panda_identify_simulated.yaml", "--force"],
}
#: Attributes that record the run, not its result.
RECORDS = ("wall_time_s", "created", "version_excite", "config_path")


def run_all(package: Path, work: Path, folder: Path, names: list[str]) -> None:
    """Each run of ``RUNS`` with the package at ``package``, written in ``work`` (the same path for
    both sides: results store their effective config, output path included), then moved into ``folder``."""
    env = {**os.environ, "PYTHONPATH": str(package)}
    code = "import sys; from excite_cli.cli import app; sys.argv[0] = 'excite'; app()"
    for name in names:
        command, config, *rest = RUNS[name]
        argv = [sys.executable, "-c", code, command, str(ROOT / config), *rest, "--output", str(work / name)]
        subprocess.run(argv, env=env, cwd=work, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.replace(work / name, folder / name)


def _attributes(a, b, where: str) -> list[str]:
    """The attributes of ``a`` and ``b`` (groups or datasets) that differ, but those of ``RECORDS``."""
    out = []
    for key in sorted(set(a.attrs) | set(b.attrs)):
        if key in RECORDS or key.startswith("version_"):
            continue
        x, y = a.attrs.get(key), b.attrs.get(key)
        if x is None or y is None or not _same(x, y):
            out.append(f"{where}@{key}")
    return out


def _same(x, y) -> bool:
    """Bit for bit; arrays holding strings (object references) by their values."""
    x, y = np.asarray(x), np.asarray(y)
    if x.dtype != y.dtype or x.shape != y.shape:
        return False
    return repr(x.tolist()) == repr(y.tolist()) if x.dtype.hasobject else x.tobytes() == y.tobytes()


def differences(a: h5py.Group, b: h5py.Group, where: str = "") -> list[str]:
    """Every dataset or attribute of ``a`` and ``b`` that is not the same bit for bit."""
    out = _attributes(a, b, where)
    for key in sorted(set(a) | set(b)):
        if key not in a or key not in b:
            out.append(f"{where}/{key} (only in one)")
        elif isinstance(a[key], h5py.Group):
            out += differences(a[key], b[key], f"{where}/{key}")
        else:
            if not _same(a[key][()], b[key][()]):
                out.append(f"{where}/{key}")
            out += _attributes(a[key], b[key], f"{where}/{key}")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("rev", help="the earlier commit")
    parser.add_argument("--quick", action="store_true", help="leave out the G1 run")
    args = parser.parse_args()
    names = [n for n in RUNS if not (args.quick and n == "g1.h5")]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for sub in ("before", "now", "work"):
            (tmp / sub).mkdir()
        subprocess.run(
            ["git", "worktree", "add", "--detach", str(tmp / "tree"), args.rev],
            cwd=ROOT,
            check=True,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            run_all(tmp / "tree", tmp / "work", tmp / "before", names)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(tmp / "tree")], cwd=ROOT, check=True)
        run_all(ROOT, tmp / "work", tmp / "now", names)
        failed = False
        for name in names:
            with h5py.File(tmp / "before" / name) as a, h5py.File(tmp / "now" / name) as b:
                found = differences(a, b)
            failed |= bool(found)
            print(f"{name:<22} {'the same bit for bit' if not found else f'{len(found)} differences'}")
            for d in found[:20]:
                print(f"    {d}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
