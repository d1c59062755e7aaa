"""A lab's robots as their files describe them (issue 59), through the commands a user types: each
description goes `excite init` → `excite check` → `excite optimize --iterations 1`, or ends in the
one line that names what to do. One line per robot:

    lab ROBOT: init ok (J active joints; held: ...), check ok, optimize -k 1: cond(C) X (exit E) in T s
    lab ROBOT: init refused: <the line>

The descriptions are made from packages on PyPI: the Panda as MJCF written by MuJoCo from
example-robot-data's URDF (Menagerie-style; pinocchio reads it), the UR10's URDF as an expanded xacro
leaves it (its meshes under `package://ur_description` in a folder that is no ROS package: refused,
then `--package-dir`, then `--no-collision`), the Kinova Jaco 2 (continuous joints 1, 4 and 6), an arm
with a Gen3 lite's gripper (a finger on a revolute joint that follows no other), the Unitree Z1 (a
gripper joint), a URDF without inertias (ROS-Industrial's KUKA iiwa) and a vendor's `.xacro` as shipped.

    .venv/bin/python bench/lab_robots.py [WORKERS]     (optimize's workers; default the cores)
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))  # the tests' builders of robot files

from conftest import CHAIN_INERTIAL, chain_urdf, panda_mjcf  # noqa: E402

from excite_cli.dynamics.robot_files import example_robot_data_root  # noqa: E402

EXCITE = [sys.executable, "-m", "excite_cli"]
ROBOTS = example_robot_data_root() / "example-robot-data" / "robots"


def _excite(args: list[str], cwd: Path) -> tuple[int, str, str]:
    """Exit status, stdout and the ``error:`` line (or the last line) of ``excite args``."""
    done = subprocess.run(EXCITE + args, cwd=cwd, capture_output=True, text=True, timeout=1800)
    lines = done.stderr.strip().splitlines()
    error = next((line for line in lines if line.startswith("error:")), lines[-1] if lines else "")
    return done.returncode, done.stdout, error


def _ur10_as_expanded(folder: Path) -> str:
    """The UR10's URDF with its meshes named ``package://ur_description/...`` and put in
    ``description/ur_description``, a folder that is no ROS package."""
    text = (ROBOTS / "ur_description" / "urdf" / "ur10_robot.urdf").read_text()
    shutil.copytree(ROBOTS / "ur_description" / "meshes", folder / "description" / "ur_description" / "meshes")
    (folder / "ur10e.urdf").write_text(
        text.replace("package://example-robot-data/robots/ur_description", "package://ur_description")
    )
    return "ur10e.urdf"


def _files(folder: Path) -> dict[str, list[list[str]]]:
    """{robot: the init argument lists tried in turn (the first that writes a config is used)}."""
    panda_mjcf(folder)
    (folder / "gen3_lite.urdf").write_text(chain_urdf(["revolute"] * 6))
    (folder / "iiwa.urdf").write_text(chain_urdf(["revolute"] * 7, gripper=False).replace(CHAIN_INERTIAL, ""))
    (folder / "arm.urdf.xacro").write_text(
        '<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:include filename="arm.xacro"/></robot>'
    )
    ur10 = _ur10_as_expanded(folder)
    return {
        "Panda MJCF": [["panda.xml"]],
        "UR10 expanded": [[ur10], [ur10, "--package-dir", "description"]],
        "UR10 no meshes": [[ur10, "--no-collision"]],
        "Jaco 2": [["kinova_description/robots/kinova.urdf"]],
        "Gen3 lite-like": [["gen3_lite.urdf"]],
        "Unitree Z1": [["z1_description/urdf/z1.urdf"]],
        "no inertias": [["iiwa.urdf"]],
        "xacro": [["arm.urdf.xacro"]],
    }


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for k, (robot, tries) in enumerate(_files(folder).items()):
            config, said = f"robot{k}.yaml", ""
            for args in tries:
                status, out, error = _excite(["init", *args, "-o", config], folder)
                if status:
                    print(f"lab {robot}: init {' '.join(args)} refused: {error}")
                    continue
                said = out
                break
            if not said:
                continue
            active = next(line for line in said.splitlines() if line.startswith("robot:")).split("(")[0]
            held = [line.split("mobile base's: ")[-1] for line in said.splitlines() if "held as a gripper's" in line]
            status, _, error = _excite(["check", config], folder)
            if status:
                print(f"lab {robot}: init ok ({active}), check refused: {error}")
                continue
            start = time.perf_counter()
            workers = ["--workers", sys.argv[1]] if len(sys.argv) > 1 else []
            status, _, error = _excite(
                ["optimize", config, "--iterations", "1", "-o", f"robot{k}.h5", *workers], folder
            )
            wall = time.perf_counter() - start
            if status not in (0, 1):
                print(f"lab {robot}: init ok ({active}), check ok, optimize refused: {error}")
                continue
            with h5py.File(folder / f"robot{k}.h5") as f:
                cond = float(f["table"]["cond_stacked"][-1])
            print(
                f"lab {robot}: init ok ({active.removeprefix('robot: ').strip()}"
                f"{'; held: ' + held[0] if held else ''}), check ok, optimize -k 1: cond(C) {cond:.1f} "
                f"(exit {status}) in {wall:.0f} s"
            )


if __name__ == "__main__":
    main()
