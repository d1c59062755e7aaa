"""Run every ```bash block of docs/guide.md, in order, in an empty folder, with the project's `excite`
first on the PATH; stop at the first command that fails (the guide cannot drift from the tool).

    .venv/bin/python docs/run_guide.py [--keep FOLDER]
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

GUIDE = Path(__file__).resolve().parent / "guide.md"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--keep", type=Path, help="run in this folder (kept) instead of a temporary one")
    args = parser.parse_args()
    blocks = re.findall(r"```bash\n(.*?)```", GUIDE.read_text(), flags=re.S)
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}", "COLUMNS": "160"}
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        for k, block in enumerate(blocks, 1):
            start = time.perf_counter()
            done = subprocess.run(
                ["bash", "-euo", "pipefail", "-c", block], cwd=folder, env=env, text=True, capture_output=True
            )
            first = block.strip().splitlines()[0]
            print(f"guide block {k}/{len(blocks)} ({time.perf_counter() - start:.0f} s): {first}")
            if done.returncode != 0:
                print(done.stdout[-3000:], done.stderr[-3000:], sep="\n")
                raise SystemExit(f"the guide's block {k} failed with status {done.returncode}")
    print(f"the guide's {len(blocks)} blocks ran")


if __name__ == "__main__":
    main()
