"""`excite init` on every arm example-robot-data ships, as a new user would run it (no --joints): each
one writes a config that passes the dry run, one with what binds at the best posture marked FIX FIRST
(no home posture), or says in one line why not. Prints one line per URDF: ``init ARM: ok in T s;
robot: ...``, ``init ARM: written in T s, with a problem to fix: ...`` or ``init ARM: refused in T s:
<the line>``.

    .venv/bin/python bench/init_arms.py
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

ARMS = [
    "panda_description/urdf/panda.urdf",
    "ur_description/urdf/ur3_robot.urdf",
    "ur_description/urdf/ur5_robot.urdf",
    "ur_description/urdf/ur10_robot.urdf",
    "kinova_description/robots/kinova.urdf",
    "xarm_description/urdf/xarm7.urdf",
    "z1_description/urdf/z1.urdf",
    "so_arm_description/urdf/so100.urdf",
    "so_arm_description/urdf/so101.urdf",
    "double_pendulum_description/urdf/double_pendulum.urdf",
    "baxter_description/urdf/baxter.urdf",
    "tiago_description/robots/tiago.urdf",
]
EXCITE = [sys.executable, "-m", "excite_cli"]


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        for arm in ARMS:
            start = time.perf_counter()
            done = subprocess.run(
                [*EXCITE, "init", arm, "-o", str(Path(folder) / "arm.yaml"), "--force"],
                capture_output=True,
                text=True,
                timeout=900,
            )
            wall = time.perf_counter() - start
            traceback = "Traceback" in done.stdout + done.stderr
            errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
            fix = next((line.strip() for line in done.stdout.splitlines() if "FIX FIRST" in line), "")
            if done.returncode == 0 and fix:
                print(f"init {arm}: written in {wall:.0f} s, with a problem to fix: {fix}")
            elif done.returncode == 0:
                joints = next((line for line in done.stdout.splitlines() if line.startswith("robot:")), "")
                print(f"init {arm}: ok in {wall:.0f} s; {joints}")
            else:
                said = errors[0] if len(errors) == 1 and not traceback else f"NOT ONE LINE (exit {done.returncode})"
                print(f"init {arm}: refused in {wall:.0f} s: {said}")


if __name__ == "__main__":
    main()
