"""``excite export``: an optimize result's trajectory as the robot plays it, written to a file."""

from __future__ import annotations

from pathlib import Path

from excite_cli.config_file import result_problem, with_overrides
from excite_cli.design.held_joints import held_joints
from excite_cli.design.resolve import build_excitation
from excite_cli.errors import ExciteError
from excite_cli.storage.export import Export, Played, check_playback, export_trajectory
from excite_cli.storage.export_files import write_export
from excite_cli.storage.formats import export_format
from excite_cli.storage.joint_map import read_joint_map, renamed
from excite_cli.storage.paths import check_target
from excite_cli.storage.results import read_alphas
from excite_cli.storage.rosbag import check_bag_target


def played_result(
    result: Path,
    iteration: int | None = None,
    rate: float = 1000.0,
    periods: int = 1,
    speed: float = 1.0,
    approach: float | None = None,
    refuse: bool = True,
) -> Export:
    """Iteration ``iteration`` (default: the last) of an ``optimize`` result sampled at ``rate`` [Hz]
    with the transitions from and to the home posture, played ``speed`` times as fast as optimized,
    and its feed-forward torques (:func:`~excite_cli.storage.export.export_trajectory` on the design
    the result stores, its regressor rows the joints' torques), the held joints' too for a standing
    robot (:func:`~excite_cli.design.held_joints.held_joints`); ``approach`` [s] before a controller's
    first point (default: :func:`~excite_cli.design.playback.approach_duration`); ``refuse``: as
    :class:`~excite_cli.storage.export.Played`'s (False for a rehearsal of what the export would refuse).

    Raises:
        ExciteError: not an excite result, an iteration it does not have, a rate, speed or period count
            out of range (:func:`~excite_cli.storage.export.check_playback`), and as ``export_trajectory``
            and ``held_joints``.
    """
    check_playback(rate, periods, speed)
    # a copy whose regressor rows are the joints' torques, the feed-forward a robot plays
    problem = with_overrides(result_problem(result), {"robot.base_wrench_rows": False})
    alphas = dict(read_alphas(result))
    k = max(alphas) if iteration is None else iteration
    if k not in alphas:
        raise ExciteError(
            "iteration", f"{result} has iterations {sorted(alphas)}, not {k}", k, f"one of {sorted(alphas)}"
        )
    excitation = build_excitation(problem)
    held = held_joints(problem.robot, problem.folder, problem.constraints, excitation.robot)
    return export_trajectory(excitation, alphas[k], Played(result, k, rate, periods, speed, approach, refuse), held)


def run_export(
    result: Path,
    iteration: int | None = None,
    rate: float = 1000.0,
    periods: int = 1,
    fmt: str = "csv",
    output: Path | None = None,
    force: bool = False,
    speed: float = 1.0,
    effort: bool = False,
    approach: float | None = None,
    joint_names: str | None = None,
) -> tuple[Export, Path]:
    """:func:`played_result` written by :func:`write_export` to ``output`` (default
    ``<result>_iteration<K>_<rate>Hz.<ending>``, the format's ending, beside the result; a
    bag is a folder of that name without an ending); a given ``output`` is checked first. ``effort``
    puts τ in a ROS 2 trajectory's points (for an effort-controlled joint_trajectory_controller);
    ``joint_names`` renames the joints as the controller names them (:mod:`~excite_cli.storage.joint_map`).

    Raises:
        ExciteError: see both and :func:`~excite_cli.storage.joint_map.renamed`, and a bad or existing
            (without ``force``) output path.
    """
    form = export_format(fmt, effort, approach)
    check = check_bag_target if form.folder else check_target
    if output is not None:
        check(output, "output", force)
    mapping = read_joint_map(joint_names) if joint_names else {}
    export = renamed(played_result(result, iteration, rate, periods, speed, approach), mapping)
    faster = f"_speed{speed:g}" if speed != 1.0 else ""
    target = output or result.with_name(f"{result.stem}_iteration{export.iteration}_{rate:g}Hz{faster}{form.suffix}")
    return export, write_export(check(target, "output", force), export, fmt, effort)
