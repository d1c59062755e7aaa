"""``excite export``: one iteration of a result as a robot plays it, at the controller's rate.

The file holds time [s], q [rad], q̇ [rad/s], q̈ [rad/s²] of the active joints and the feed-forward
torque τ = RNEA(q, q̇, q̈) [Nm] of the URDF model (base held fixed, locked joints at their values):
a quintic transition from the home posture at rest, P periods of the trajectory, a transition back
(:mod:`excite_cli.design.playback`), at the optimized speed or ``speed`` times faster. Every
constraint of the problem is checked again on the exported samples; a file that violates one is not
written, except for predictions the robot's own control decides (the zero-moment point,
:attr:`~excite_cli.constraints.constraint.Constraint.advisory`), which are reported and warned about.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from excite_cli.atomic import atomic_path
from excite_cli.design.excitation import Excitation
from excite_cli.design.playback import check_motion, plan_playback
from excite_cli.errors import ExciteError
from excite_cli.storage.formats import export_format
from excite_cli.storage.rosbag import check_goal_size, write_rosbag
from excite_cli.storage.trajectory_controller import controller_refusals, time_from_start_ns

#: Highest export rate accepted [Hz] (memory grows with rate × duration).
MAX_RATE = 100_000.0
#: Most periods accepted.
MAX_PERIODS = 1000
#: Fastest and slowest playback accepted (times the optimized speed).
MAX_SPEED, MIN_SPEED = 10.0, 0.01
#: Most samples in one file (about 1.3 GB of CSV with 7 joints).
MAX_SAMPLES = 20_000_000


@dataclass(frozen=True)
class Export:
    """Samples of a played trajectory.

    Attributes:
        joint_names: (n,) active joints.
        time: (S,) [s] at k / rate; q, qd, qdd: (S, n) [rad, rad/s, rad/s²]; tau: (S, n) [Nm].
        rate: [Hz]; iteration: the result's iteration k; periods: periods of the trajectory.
        segments: (name, start [s], duration [s]) of the transitions and periods, in order.
        max_violation: largest normalized constraint violation on the samples (≤ 0: satisfied).
        worst: the constraint and place of ``max_violation``, in words.
        speed: times the optimized speed the motion is played (q̇ scales by it, q̈ by its square).
        predictions: what the advisory constraints (the zero-moment point) predict on the samples, in words.
        warnings: the advisory constraints the samples violate, in words.
    """

    joint_names: list[str]
    time: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    rate: float
    iteration: int
    periods: int
    segments: list[tuple[str, float, float]]
    max_violation: float
    worst: str
    speed: float = 1.0
    predictions: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()


class Played(NamedTuple):
    """How one iteration of a result is exported: ``result`` (named in the messages), its ``iteration``,
    the ``rate`` [Hz], the ``periods`` of the trajectory, and the ``speed`` (times the optimized)."""

    result: Path
    iteration: int
    rate: float
    periods: int
    speed: float


def check_playback(rate: float, periods: int, speed: float) -> None:
    """Refuse an export rate [Hz], period count or speed out of range (before anything is read).

    Raises:
        ExciteError: (``rate``, ``speed``, ``periods``) a value outside (0, ``MAX_RATE``],
            [``MIN_SPEED``, ``MAX_SPEED``] or [1, ``MAX_PERIODS``].
    """
    if not (np.isfinite(rate) and 0.0 < rate <= MAX_RATE):
        raise ExciteError("rate", f"{rate:g} Hz is out of range", rate, f"(0, {MAX_RATE:g}] Hz")
    if not (np.isfinite(speed) and MIN_SPEED <= speed <= MAX_SPEED):
        raise ExciteError("speed", f"{speed:g} is out of range", speed, f"{MIN_SPEED:g} to {MAX_SPEED:g}")
    if not 1 <= periods <= MAX_PERIODS:
        raise ExciteError("periods", f"{periods} is out of range", periods, f"1 to {MAX_PERIODS}")


def export_trajectory(excitation: Excitation, alpha: np.ndarray, how: Played) -> Export:
    """Sample the trajectory of Fourier coefficients ``alpha`` (n, 2N+1) of ``excitation`` (its regressor
    rows the joints' torques) as ``how`` says, with the transitions from and to the home posture, and
    its feed-forward torques. ``how``'s rate, periods and speed are :func:`check_playback`'s.

    Raises:
        ExciteError: α of another shape than the excitation's, a rate below the trajectory's Nyquist
            rate, more than ``MAX_SAMPLES`` samples, or samples that violate a constraint that is not
            advisory (the message names it).
    """
    result, k, rate, periods, speed = how
    if alpha.shape != (excitation.robot.n_joints, excitation.trajectory.n_coefficients):
        raise ExciteError(
            "result",
            f"{result}: iteration {k} has α of shape {alpha.shape}, its config needs "
            f"{(excitation.robot.n_joints, excitation.trajectory.n_coefficients)}",
        )
    nyquist = speed * excitation.trajectory.nyquist_rate
    if rate <= nyquist:
        played = f" played at speed {speed:g}" if speed != 1.0 else ""
        raise ExciteError(
            "rate",
            f"{rate:g} Hz cannot represent the trajectory{played} (its highest harmonic needs more than "
            f"{nyquist:.3g} Hz)",
            rate,
            f"more than {nyquist:.3g} Hz",
        )
    try:
        playback = plan_playback(excitation, alpha, periods)
    except ExciteError as exc:  # a stored α the optimizer cannot have written (edited, corrupt)
        raise ExciteError("result", f"{result}: iteration {k}: {exc.field}: {exc.problem}") from None
    duration = playback.duration / speed
    if duration * rate > MAX_SAMPLES:
        raise ExciteError(
            "rate",
            f"{duration:.0f} s at {rate:g} Hz is {duration * rate:.3g} samples; "
            f"at most {MAX_SAMPLES:.0e} fit in one file (lower the rate or the periods)",
        )
    time, q, qd, qdd = playback.sample(rate, speed=speed)
    binding = [c for c in excitation.constraints if not c.advisory]
    violation, worst = check_motion(binding, time, q, qd, qdd)
    played = f" at speed {speed:g}" if speed != 1.0 else ""
    if violation > 0.0:
        raise ExciteError(
            "result", f"{result}: iteration {k} played{played} at {rate:g} Hz violates {worst}; no file written"
        )
    advisory = [(c, c.check_samples(time, q, qd, qdd)) for c in excitation.constraints if c.advisory]
    robot = excitation.robot
    tau = np.array([robot.torques(*x) for x in zip(q, qd, qdd)])
    starts = np.cumsum([0.0] + [s.duration for s in playback.segments])
    return Export(
        joint_names=list(robot.joint_names),
        time=time,
        q=q,
        qd=qd,
        qdd=qdd,
        tau=tau,
        rate=rate,
        iteration=k,
        periods=periods,
        segments=[(s.name, float(t0) / speed, s.duration / speed) for s, t0 in zip(playback.segments, starts)],
        max_violation=violation,
        worst=worst,
        speed=speed,
        predictions=tuple(f"{c.field}: {check.where}" for c, check in advisory),
        warnings=tuple(
            f"{c.field}: played{played}, the {check.where}, less than the margin the config asks: the robot may tip"
            for c, check in advisory
            if check.max_violation > 0.0
        ),
    )


def columns(joint_names: list[str]) -> list[str]:
    """Column names with units: ``time_s``, ``q_<joint>_rad``, ``qd_<joint>_rad_s``,
    ``qdd_<joint>_rad_s2``, ``tau_<joint>_Nm``."""
    return ["time_s"] + [
        f"{x}_{j}_{unit}"
        for x, unit in (("q", "rad"), ("qd", "rad_s"), ("qdd", "rad_s2"), ("tau", "Nm"))
        for j in joint_names
    ]


def write_export(path: Path, export: Export, fmt: str = "csv", effort: bool = False) -> Path:
    """Write ``export`` as CSV (``#`` comment lines, then one header row of :func:`columns`), NPZ
    (arrays ``time``, ``q``, ``qd``, ``qdd``, ``tau``, ``joint_names``, ``columns``), a ROS 2
    FollowJointTrajectory goal (:func:`ros2_goal`) or a ROS 2 bag folder
    (:func:`~excite_cli.storage.rosbag.write_rosbag`), atomically. The ROS 2 formats carry τ as the
    points' effort only with ``effort`` (for an effort-controlled joint_trajectory_controller), and
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


def _write_bag(path: Path, export: Export, effort: bool) -> Path:
    motion = (export.q, export.qd, export.qdd, export.tau)
    return write_rosbag(path, export.joint_names, export.time, motion, effort=effort)


def _write_goal(path: Path, export: Export, effort: bool) -> Path:
    goal = ros2_goal(export, effort)
    check_goal_size(goal)
    with atomic_path(path, "output") as tmp:
        tmp.write_text(goal, encoding="utf-8")
    return path


def _write_npz(path: Path, export: Export, effort: bool) -> Path:
    arrays = {"time": export.time, "q": export.q, "qd": export.qd, "qdd": export.qdd, "tau": export.tau}
    names = {"joint_names": np.array(export.joint_names), "columns": np.array(columns(export.joint_names))}
    with atomic_path(path, "output") as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays, **names)
    return path


def _write_csv(path: Path, export: Export, effort: bool) -> Path:
    table = np.column_stack([export.time, export.q, export.qd, export.qdd, export.tau])
    comments = [
        f"excite export: iteration {export.iteration}, {export.rate:g} Hz, {export.periods} period(s)",
        "segments: " + "; ".join(f"{n} {t0:.3f}-{t0 + d:.3f} s" for n, t0, d in export.segments),
        "tau: feed-forward RNEA torque of the URDF model",
        f"largest constraint violation (normalized, <= 0 satisfied): {export.max_violation:.3g}",
    ]
    with atomic_path(path, "output") as tmp, open(tmp, "w") as f:
        f.write("".join(f"# {line}\n" for line in comments))
        np.savetxt(f, table, delimiter=",", header=",".join(columns(export.joint_names)), comments="", fmt="%.10g")
    return path


#: What writes each format (:data:`~excite_cli.storage.formats.FORMATS`), by its name.
_WRITERS = {"csv": _write_csv, "npz": _write_npz, "ros2": _write_goal, "rosbag2": _write_bag}


def _check_controller_accepts(export: Export, effort: bool) -> None:
    """That the joint_trajectory_controller accepts the trajectory ``export`` writes.

    Raises:
        ExciteError: its first refusal, in the controller's words.
    """
    refusals = controller_refusals(
        export.joint_names,
        time_from_start_ns(export.time),
        export.q,
        export.qd,
        export.qdd,
        export.tau if effort else None,
        effort_interface=effort,
    )
    if refusals:
        raise ExciteError("format", f"joint_trajectory_controller would refuse the trajectory: {refusals[0]}")


def ros2_goal(export: Export, effort: bool = False) -> str:
    """``export`` as the YAML of a ``control_msgs/action/FollowJointTrajectory`` goal: its
    ``trajectory`` (``trajectory_msgs/msg/JointTrajectory``) with the URDF's joint names and one
    point per sample (``positions`` [rad], ``velocities`` [rad/s], ``accelerations`` [rad/s²],
    ``time_from_start`` as sec and nanosec; ``effort`` [Nm], the feed-forward torque, with ``effort``),
    e.g. for ``ros2 action send_goal /<controller>/follow_joint_trajectory
    control_msgs/action/FollowJointTrajectory "$(cat FILE)"`` (at most 128 KiB: one argument)."""

    def numbers(row: np.ndarray) -> str:
        return "[" + ", ".join(f"{x:.10g}" for x in row) + "]"

    nanoseconds = time_from_start_ns(export.time)
    lines = [
        f"# excite export: iteration {export.iteration}, {export.rate:g} Hz, {export.periods} period(s)",
        "trajectory:",
        f"  joint_names: [{', '.join(export.joint_names)}]",
        "  points:",
    ]
    for k, ns in enumerate(nanoseconds):
        torque = f"effort: {numbers(export.tau[k])}, " if effort else ""
        lines.append(
            f"  - {{positions: {numbers(export.q[k])}, velocities: {numbers(export.qd[k])}, "
            f"accelerations: {numbers(export.qdd[k])}, {torque}"
            f"time_from_start: {{sec: {ns // 10**9}, nanosec: {ns % 10**9}}}}}"
        )
    return "\n".join(lines) + "\n"
