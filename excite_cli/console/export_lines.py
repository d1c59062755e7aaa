"""What ``export`` prints: the played motion's segments and checks, the file written and, for the
ROS 2 formats, how the controller gets it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from excite_cli.storage.export import Export
from excite_cli.storage.formats import FORMATS
from excite_cli.storage.rosbag import ACKED_WAIT_MS, PLAY_DELAY_S, TOPIC


def export_lines(e: Export, rate: float, target: Path, fmt: str, effort: bool = False) -> list[str]:
    """The segments of an exported motion, its constraint check, the file written and, for a ROS 2
    bag, how to play it and record the run; for the ROS 2 formats, whether the points carry ``effort``."""
    faster = f", played at {e.speed:g} × the optimized speed" if e.speed != 1.0 else ""
    lines = [f"{name:>15}: {start:8.3f} s → {start + duration:8.3f} s" for name, start, duration in e.segments] + [
        f"{e.time.size} samples at {rate:g} Hz{faster}; every constraint holds: largest normalized violation "
        f"{e.max_violation:+.2e} (≤ 0 satisfied), closest: {e.worst}",
        *[f"predicted (feet flat, legs rigid): {p}" for p in e.predictions],
        *held_lines(e),
        *[f"warning: {w}" for w in e.warnings],
        f"wrote {target}",
    ]
    form = FORMATS[fmt]
    if e.held and form.controller:
        lines.append(
            f"held joints ({len(e.held.joint_names)}): in the trajectory, held still with their feed-forward as "
            "effort, for one effort-controlled controller over the whole body"
            if effort
            else "held joints: not in the trajectory (--effort puts them in with their feed-forward); "
            "their torques are in the csv and npz formats"
        )
    if form.folder:
        lines += [
            f"play it: ros2 bag play {target} --delay {PLAY_DELAY_S:g} --wait-for-all-acked {ACKED_WAIT_MS}  "
            f"(the controller's subscription matched first, the message acknowledged before the player ends; "
            f"another controller: --remap {TOPIC}:=/<controller>/joint_trajectory)",
            f"record the run meanwhile: ros2 bag record /joint_states -o {target.name}_run_1  "
            "(excite identify reads that bag folder as a data.runs file)",
        ]
    if form.controller:
        lines += approach_lines(e)
        lines.append(
            "effort: the feed-forward torque, for an effort-controlled joint_trajectory_controller (Jazzy on)"
            if effort
            else "positions, velocities and accelerations: what every joint_trajectory_controller accepts "
            "(--effort adds the feed-forward torque, for an effort-controlled one)"
        )
    return lines


def approach_lines(e: Export) -> list[str]:
    """When a controller's first point comes, and a warning where a given ``--approach`` is shorter than
    the time from anywhere in the joint range, naming that time and how near home each joint must start."""
    line = (
        f"first point (home, at rest) at {e.approach:g} s: the controller moves the robot there from where it "
        "stands in that time"
    )
    if not e.reach:
        anywhere = " (from anywhere in its joint range within the velocity and acceleration limits; --approach sets it)"
        return [line + anywhere]
    near = ", ".join(f"{name} {d:.3g} rad" for name, d in e.reach)
    return [
        line,
        f"warning: --approach {e.approach:g} s is shorter than the {e.approach_needed:g} s the controller needs from "
        f"anywhere in the joint range within the velocity and acceleration limits; in {e.approach:g} s it brings "
        f"home only a robot that starts within {near} of it (start it nearer home, or leave --approach out)",
    ]


def held_lines(e: Export) -> list[str]:
    """For a standing robot: the held joints' feed-forward, its largest torque against its effort limit."""
    if not e.held:
        return []
    k, share = e.held.peak()
    name, peak, limit = e.held.joint_names[k], np.abs(e.held.tau[:, k]).max(), e.held.effort[k]
    against = (
        f"{100 * share:.0f} % of its effort limit {limit:g} Nm" if np.isfinite(limit) and limit > 0 else "no limit"
    )
    return [
        f"held joints ({len(e.held.joint_names)}): feed-forward that keeps the base and them still, feet flat; "
        f"largest share {name} {peak:.1f} Nm ({against})"
    ]
