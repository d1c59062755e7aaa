"""``view``: the motion a robot would play (transition in, one period, transition out), as a 3D
scene in one HTML file (:func:`excite_cli.plots.scene.write_scene`), to look at before running it."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from excite_cli.collision.world import world_shapes
from excite_cli.config_file import result_problem
from excite_cli.dynamics.robot import load_robot
from excite_cli.errors import ExciteError
from excite_cli.plots.scene import write_scene
from excite_cli.storage.paths import check_target
from excite_cli.workflows.export import played_result

#: Highest frame rate of a scene [Hz] (the file grows with frames × meshes).
MAX_FRAME_RATE = 120.0


def run_view(
    result: Path,
    iteration: Optional[int] = None,
    output: Optional[Path] = None,
    rate: float = 30.0,
    force: bool = False,
) -> Path:
    """Write the scene of ``iteration`` (default: the last) of an ``optimize`` result to ``output``
    (default ``<result>_iteration<K>.html`` beside it), ``rate`` frames per second; returns the path.

    Raises:
        ExciteError: not a result, an unknown iteration, a rate outside (0, MAX_FRAME_RATE], a bad
            or existing (without ``force``) output path.
    """
    if not 0.0 < rate <= MAX_FRAME_RATE:
        raise ExciteError("rate", f"{rate:g} Hz is out of range", rate, f"(0, {MAX_FRAME_RATE:g}] frames per second")
    if output is not None:
        check_target(output, "output", force)
    played = played_result(result, iteration, rate)
    target = check_target(
        output or result.with_name(f"{result.stem}_iteration{played.iteration}.html"), "output", force
    )
    problem = result_problem(result)
    robot = load_robot(problem.robot, problem.folder, collision=True)
    return write_scene(target, robot, played.q, rate, world_shapes(problem.constraints.environment))
