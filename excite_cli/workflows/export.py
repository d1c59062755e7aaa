"""``excite export``: an optimize result's trajectory as the robot plays it, written to a file."""

from __future__ import annotations

from pathlib import Path

from excite_cli.storage.export import Export, export_trajectory, write_export
from excite_cli.storage.formats import FORMATS, check_format
from excite_cli.storage.paths import check_target
from excite_cli.storage.rosbag import check_bag_target


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
) -> tuple[Export, Path]:
    """:func:`export_trajectory` written by :func:`write_export` to ``output`` (default
    ``<result>_iteration<K>_<rate>Hz.<ending>``, the ending of :data:`FORMATS`, beside the result; a
    bag is a folder of that name without an ending); a given ``output`` is checked first. ``effort``
    puts τ in a ROS 2 trajectory's points (for an effort-controlled joint_trajectory_controller).

    Raises:
        ExciteError: see both, and a bad or existing (without ``force``) output path.
    """
    check_format(fmt, effort)
    check = check_bag_target if fmt == "rosbag2" else check_target
    if output is not None:
        check(output, "output", force)
    export = export_trajectory(result, iteration, rate, periods, speed)
    ending = f".{FORMATS[fmt]}" if FORMATS[fmt] else ""
    faster = f"_speed{speed:g}" if speed != 1.0 else ""
    target = output or result.with_name(f"{result.stem}_iteration{export.iteration}_{rate:g}Hz{faster}{ending}")
    return export, write_export(check(target, "output", force), export, fmt, effort)
