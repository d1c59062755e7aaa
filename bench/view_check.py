"""Does `excite view` show the robot in a browser? Writes the scene of a result and the same scene
without the robot's meshes (the world shapes in both), takes a screenshot of each in headless Chromium (WebGL by SwiftShader)
and counts the pixels where they differ: the robot. Exit status 1 below ``MIN_PIXELS``.

Run: `make view-check` (installs Debian's chromium when missing, as root; see the Makefile) or
`.venv/bin/python bench/view_check.py [RESULT.h5]` (default results/smoke.h5, from `make smoke`).
The screenshots are kept beside the result for a person to look at.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import matplotlib.image
import numpy as np
import pinocchio as pin

from excite_cli.collision.world import world_shapes
from excite_cli.config_file import result_problem
from excite_cli.dynamics.robot import load_robot
from excite_cli.plots.scene import write_scene
from excite_cli.workflows.export import played_result
from excite_cli.workflows.view import run_view

#: Pixels that must change when the robot is drawn (of 1000 × 700).
MIN_PIXELS = 2000


def screenshot(browser: str, html: Path) -> np.ndarray:
    """(H, W, 3) RGB in [0, 1] of ``html`` after 3 s of the browser's virtual time."""
    png = html.with_suffix(".png")
    command = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader"]
    command += ["--enable-unsafe-swiftshader", "--window-size=1000,700", "--virtual-time-budget=3000"]
    subprocess.run(
        [*command, f"--screenshot={png}", html.resolve().as_uri()], capture_output=True, timeout=180, check=True
    )
    return matplotlib.image.imread(png)[..., :3]


def main(result: Path) -> int:
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        print("view check skipped: no chromium (make view-check installs it as root)")
        return 0
    scene = run_view(result, output=result.with_name(result.stem + "_view.html"), rate=10.0, force=True)
    problem = result_problem(result)
    robot = replace(load_robot(problem.robot, problem.folder, collision=True), collision_model=pin.GeometryModel())
    shapes = world_shapes(problem.constraints.environment)  # drawn in both: only the robot's pixels differ
    played = played_result(result, rate=10.0).q
    empty = write_scene(result.with_name(result.stem + "_view_empty.html"), robot, played, 10.0, shapes)
    changed = int((np.abs(screenshot(browser, scene) - screenshot(browser, empty)).max(axis=2) > 0.1).sum())
    print(f"{scene}: {changed} pixels show the robot (at least {MIN_PIXELS}); screenshot {scene.with_suffix('.png')}")
    return 0 if changed >= MIN_PIXELS else 1


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("results/smoke.h5")))
