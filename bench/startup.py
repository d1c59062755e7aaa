"""Start-up of the command line: wall time of `excite --version` and `excite --help` in a fresh
interpreter, median of 10 each, beside `python -c "import typer, rich"` (the frame's own floor) in the
same run.

    .venv/bin/python bench/startup.py
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time


def median_wall(argv: list[str], runs: int = 10) -> float:
    """Median wall time [s] of ``runs`` runs of ``argv``."""
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(argv, check=True, capture_output=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    cases = {
        'python -c "import typer, rich"': [sys.executable, "-c", "import typer, rich"],
        "excite --version": [sys.executable, "-m", "excite_cli", "--version"],
        "excite --help": [sys.executable, "-m", "excite_cli", "--help"],
    }
    for name, argv in cases.items():
        print(f"startup {name}: {median_wall(argv):.2f} s (median of 10)", flush=True)


if __name__ == "__main__":
    main()
