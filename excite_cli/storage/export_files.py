"""The files ``excite export`` writes from a played motion (:class:`~excite_cli.storage.export.Export`):
CSV and NPZ for any controller, a ROS 2 FollowJointTrajectory goal and a ROS 2 bag for ros2_control's
joint_trajectory_controller, all written atomically. The ROS 2 formats' first point (the home posture at
rest) is at ``time_from_start`` = the export's approach, not 0: the controller samples a first point
whose time is not in the future at once (``trajectory.cpp``), a step from wherever the robot stands;
given time, it interpolates there from its current state. The CSV and NPZ keep time 0 at home.

A standing robot's export also holds the held joints' feed-forward
(:mod:`~excite_cli.design.held_joints`): CSV columns ``tau_<joint>_Nm`` after the active joints'
(the header names the held joints and the values they are held at), NPZ arrays; in the ROS 2 formats
with ``effort`` the held joints are points of the same trajectory, at their held values at rest, their
effort the feed-forward, for one effort-controlled joint_trajectory_controller over the whole body,
which adds each point's effort to its PID's command (ros2_controllers ≥ 4.22, the change "Enable
feed-forward effort trajectories", its user documentation). Without ``effort`` the trajectory names the
active joints only, as a position-controlled arm controller accepts it (the controller refuses a joint
it does not command).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from excite_cli.atomic import MARK, atomic_path
from excite_cli.errors import ExciteError
from excite_cli.storage.export import Export
from excite_cli.storage.formats import export_format
from excite_cli.storage.rosbag import check_goal_size, write_rosbag
from excite_cli.storage.trajectory_controller import controller_refusals, time_from_start_ns


def columns(joint_names: list[str], held_names: tuple[str, ...] = ()) -> list[str]:
    """Column names with units: ``time_s``, ``q_<joint>_rad``, ``qd_<joint>_rad_s``,
    ``qdd_<joint>_rad_s2``, ``tau_<joint>_Nm`` of the active joints, then ``tau_<joint>_Nm`` of the
    held joints ``held_names``."""
    return (
        ["time_s"]
        + [
            f"{x}_{j}_{unit}"
            for x, unit in (("q", "rad"), ("qd", "rad_s"), ("qdd", "rad_s2"), ("tau", "Nm"))
            for j in joint_names
        ]
        + [f"tau_{j}_Nm" for j in held_names]
    )


def write_export(path: Path, export: Export, fmt: str = "csv", effort: bool = False) -> Path:
    """Write ``export`` as CSV (``#`` comment lines, then one header row of :func:`columns`), NPZ
    (arrays ``time``, ``q``, ``qd``, ``qdd``, ``tau``, ``joint_names``, ``columns``, and for a standing
    robot ``held_joint_names``, ``held_positions``, ``tau_held``), a ROS 2 FollowJointTrajectory goal
    (:func:`ros2_goal`) or a ROS 2 bag folder (:func:`~excite_cli.storage.rosbag.write_rosbag`),
    atomically. The ROS 2 formats carry τ as the points' effort only with ``effort`` (for an
    effort-controlled joint_trajectory_controller; the held joints then too, module docstring), and
    are checked against that controller's rules first (:mod:`~excite_cli.storage.trajectory_controller`).

    Raises:
        ExciteError: an unknown format, ``effort`` for a data file (which always holds τ), a trajectory
            the controller would refuse, a goal longer than one command-line argument holds
            (:func:`~excite_cli.storage.rosbag.check_goal_size`), or a file that cannot be written.
    """
    form = export_format(fmt, effort)
    if form.controller:
        _check_controller_accepts(export, effort)
    return _WRITERS[form.name](Path(path), export, effort)


def controller_motion(export: Export, effort: bool) -> tuple[list[str], tuple[np.ndarray, ...]]:
    """The joint names (m,) and q, q̇, q̈, τ (S, m) a joint_trajectory_controller gets: the active
    joints, and with ``effort`` the held joints after them (held still, τ their feed-forward)."""
    motion = (export.q, export.qd, export.qdd, export.tau)
    if not (effort and export.held):
        return list(export.joint_names), motion
    held, count = export.held, export.time.size
    still = np.zeros((count, len(held.joint_names)))
    added = (still + held.positions, still, still, held.tau)
    return list(export.joint_names) + list(held.joint_names), tuple(np.hstack(x) for x in zip(motion, added))


def _write_bag(path: Path, export: Export, effort: bool) -> Path:
    names, motion = controller_motion(export, effort)
    return write_rosbag(path, names, export.time + export.approach, motion, effort=effort)


def _write_goal(path: Path, export: Export, effort: bool) -> Path:
    goal = ros2_goal(export, effort)
    check_goal_size(goal)
    with atomic_path(path, "output") as tmp:
        tmp.write_text(goal, encoding="utf-8")
    return path


def _write_npz(path: Path, export: Export, effort: bool) -> Path:
    arrays = {"time": export.time, "q": export.q, "qd": export.qd, "qdd": export.qdd, "tau": export.tau}
    held = export.held.joint_names if export.held else ()
    names = {"joint_names": np.array(export.joint_names), "columns": np.array(columns(export.joint_names, held))}
    names["written_by"] = np.array(f"{MARK} export")
    if export.held:
        arrays |= {"held_positions": export.held.positions, "tau_held": export.held.tau}
        names["held_joint_names"] = np.array(held)
    with atomic_path(path, "output") as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays, **names)
    return path


def _write_csv(path: Path, export: Export, effort: bool) -> Path:
    held = export.held
    table = np.column_stack([export.time, export.q, export.qd, export.qdd, export.tau] + ([held.tau] if held else []))
    with atomic_path(path, "output") as tmp, open(tmp, "w") as f:  # the column names first, for any reader
        header = ",".join(columns(export.joint_names, held.joint_names if held else ()))
        np.savetxt(f, table, delimiter=",", header=header, comments="", fmt="%.10g")
        f.write("".join(f"# {line}\n" for line in csv_notes(export)))
    return path


def csv_notes(export: Export) -> list[str]:
    """What the CSV's ``#`` lines after its rows say: the export, its segments, what each group of
    torque columns is (for held joints the rule that split the ground force between the soles), the
    held joints' peak against its URDF limit and their positions, the largest constraint violation, the
    export's warnings; the mark last."""
    held = export.held
    at_rest = " with the base and the held joints at rest" if held else ""
    notes = [
        f"excite export: iteration {export.iteration}, {export.rate:g} Hz, {export.periods} period(s), "
        f"speed {export.speed:g}",
        "segments: " + "; ".join(f"{n} {t0:.3f}-{t0 + d:.3f} s" for n, t0, d in export.segments),
        f"tau of the active joints ({len(export.joint_names)} columns after qdd): inverse dynamics (RNEA) of the "
        f"URDF's rigid model at the row's q, qd, qdd{at_rest}",
        f"largest constraint violation (normalized, <= 0 satisfied): {export.max_violation:.3g}",
    ]
    if held:
        k, share = held.peak()
        limited = 0 < held.effort[k] < np.inf
        peak = np.abs(held.tau[:, k]).max()
        notes += [
            f"tau of the held joints ({len(held.joint_names)} columns after the active joints'): the feed-forward "
            "that keeps the base and them at rest, feet flat: inverse dynamics of their rows minus the torques of "
            f"the contact forces at the soles' {len(held.points)} points, the ground wrench split as the "
            f"least-norm forces, or where one leaves its friction cone (mu {held.friction:g}) the least-norm "
            "forces inside the cones; another split moves these torques, not the active joints'",
            f"held joints' peak: {held.joint_names[k]} {peak:.4g} Nm"
            + (f", {100 * share:.0f} % of its URDF limit {held.effort[k]:g} Nm" if limited else " (no URDF limit)"),
            "held joints (not moved): "
            + ", ".join(f"{name} at {value:.6g} rad" for name, value in zip(held.joint_names, held.positions)),
        ]
    return notes + [f"warning: {w}" for w in export.warnings] + [f"{MARK} export"]


#: What writes each format (:data:`~excite_cli.storage.formats.FORMATS`), by its name.
_WRITERS = {"csv": _write_csv, "npz": _write_npz, "ros2": _write_goal, "rosbag2": _write_bag}


def _check_controller_accepts(export: Export, effort: bool) -> None:
    """That the joint_trajectory_controller accepts the trajectory ``export`` writes.

    Raises:
        ExciteError: its first refusal, in the controller's words.
    """
    names, (q, qd, qdd, tau) = controller_motion(export, effort)
    time_ns = time_from_start_ns(export.time + export.approach)
    refusals = controller_refusals(names, time_ns, q, qd, qdd, tau if effort else None, effort_interface=effort)
    if refusals:
        raise ExciteError("format", f"joint_trajectory_controller would refuse the trajectory: {refusals[0]}")


def ros2_goal(export: Export, effort: bool = False) -> str:
    """``export`` as the YAML of a ``control_msgs/action/FollowJointTrajectory`` goal: its
    ``trajectory`` (``trajectory_msgs/msg/JointTrajectory``) with the URDF's joint names and one
    point per sample (``positions`` [rad], ``velocities`` [rad/s], ``accelerations`` [rad/s²],
    ``time_from_start`` as sec and nanosec; ``effort`` [Nm], the feed-forward torque, with ``effort``,
    the held joints then too: :func:`controller_motion`), e.g. for ``ros2 action send_goal
    /<controller>/follow_joint_trajectory control_msgs/action/FollowJointTrajectory "$(cat FILE)"``
    (at most 128 KiB: one argument)."""

    def numbers(row: np.ndarray) -> str:
        return "[" + ", ".join(f"{x:.10g}" for x in row) + "]"

    names, (q, qd, qdd, tau) = controller_motion(export, effort)
    nanoseconds = time_from_start_ns(export.time + export.approach)
    lines = [
        f"# {MARK} export",
        f"# excite export: iteration {export.iteration}, {export.rate:g} Hz, {export.periods} period(s)",
        "trajectory:",
        f"  joint_names: [{', '.join(names)}]",
        "  points:",
    ]
    for k, ns in enumerate(nanoseconds):
        torque = f"effort: {numbers(tau[k])}, " if effort else ""
        lines.append(
            f"  - {{positions: {numbers(q[k])}, velocities: {numbers(qd[k])}, "
            f"accelerations: {numbers(qdd[k])}, {torque}"
            f"time_from_start: {{sec: {ns // 10**9}, nanosec: {ns % 10**9}}}}}"
        )
    return "\n".join(lines) + "\n"
