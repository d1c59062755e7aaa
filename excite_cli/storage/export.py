"""``excite export``: one iteration of a result as a robot plays it, at the controller's rate.

The file holds time [s], q [rad], q̇ [rad/s], q̈ [rad/s²] of the active joints and the feed-forward
torque τ = RNEA(q, q̇, q̈) [Nm] of the URDF model (base held fixed, locked joints at their values):
a quintic transition from the home posture at rest, P periods of the trajectory, a transition back
(:mod:`excite_cli.design.playback`), at the optimized speed or ``speed`` times faster. Every
constraint of the problem is checked again on the exported samples; a file that violates one is not
written, except for predictions the robot's own control decides (the zero-moment point,
:attr:`~excite_cli.constraints.constraint.Constraint.advisory`), which are reported and warned about.
A standing robot's export also holds its held joints' feed-forward
(:mod:`~excite_cli.design.held_joints`), refused where it exceeds a URDF effort limit.
:mod:`~excite_cli.storage.export_files` writes it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from excite_cli.constraints.constraint import Constraint
from excite_cli.constraints.zmp import has_floating_base
from excite_cli.design.excitation import Excitation
from excite_cli.design.held_joints import HeldJoints, HeldTorques
from excite_cli.design.playback import Playback, approach_duration, approach_shortfall, check_motion, plan_playback
from excite_cli.errors import ExciteError

#: Highest export rate accepted [Hz] (memory grows with rate × duration).
MAX_RATE = 100_000.0
#: Most periods accepted.
MAX_PERIODS = 1000
#: Fastest and slowest playback accepted (times the optimized speed).
MAX_SPEED, MIN_SPEED = 10.0, 0.01
#: Resolution of the largest passing speed a refusal names.
SPEED_STEP = 0.01
#: Longest approach accepted [s].
MAX_APPROACH = 600.0
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
        warnings: the advisory constraints the samples violate, and the samples whose held-joint
            feed-forward found no contact forces inside the friction cones, in words.
        held: a standing robot's held joints and their feed-forward at the samples, or None.
        approach: [s] what a controller's trajectory waits before its first point (the home posture at
            rest), its time to bring the robot there from where it stands; the ROS 2 formats start
            their points' ``time_from_start`` there (:func:`~excite_cli.design.playback.approach_duration`).
        approach_needed: [s] that time from anywhere in the joint range (``approach`` unless one was given).
        reach: (joint, [rad]) of the joints a shorter given ``approach`` brings home only from within that
            distance of it (:func:`~excite_cli.design.playback.approach_shortfall`), else empty.
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
    held: HeldTorques | None = None
    approach: float = 0.0
    approach_needed: float = 0.0
    reach: tuple[tuple[str, float], ...] = ()


class Played(NamedTuple):
    """How one iteration of a result is exported: ``result`` (named in the messages), its ``iteration``,
    the ``rate`` [Hz], the ``periods`` of the trajectory, the ``speed`` (times the optimized) and the
    ``approach`` [s] before the first point (None: :func:`~excite_cli.design.playback.approach_duration`);
    ``refuse``: a violated limit refuses the samples (False: it is kept in the export's
    ``max_violation`` and ``worst``, for a rehearsal that plays what the export would refuse)."""

    result: Path
    iteration: int
    rate: float
    periods: int
    speed: float
    approach: float | None = None
    refuse: bool = True


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


def export_trajectory(excitation: Excitation, alpha: np.ndarray, how: Played, held: HeldJoints | None = None) -> Export:
    """Sample the trajectory of Fourier coefficients ``alpha`` (n, 2N+1) of ``excitation`` (its regressor
    rows the joints' torques) as ``how`` says, with the transitions from and to the home posture, and
    its feed-forward torques, with ``held``'s for a standing robot. ``how``'s rate, periods and speed
    are :func:`check_playback`'s.

    Raises:
        ExciteError: α of another shape than the excitation's, a rate below the trajectory's Nyquist
            rate, more than ``MAX_SAMPLES`` samples, and where ``how.refuse``: samples that violate a
            constraint that is not advisory (the message names it), or a held joint's feed-forward above
            its URDF effort limit.
    """
    result, k, rate, periods, speed, approach, refuse = how
    if approach is not None and not (np.isfinite(approach) and 0.0 <= approach <= MAX_APPROACH):
        raise ExciteError("approach", f"{approach:g} s is out of range", approach, f"0 to {MAX_APPROACH:g} s")
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
    if violation > 0.0 and refuse:
        fastest = fastest_passing(playback, binding, rate, speed)
        passes = f"; the largest speed that passes: {fastest:.2f}" if fastest else ""
        raise ExciteError(
            "result",
            f"{result}: iteration {k} played{played} at {rate:g} Hz violates {worst}{passes}; no file written",
        )
    advisory = [(c, c.check_samples(time, q, qd, qdd)) for c in excitation.constraints if c.advisory]
    stance = None if held is None else held.torques(q, qd, qdd)
    if stance is not None and refuse:
        _check_held_efforts(stance, f"{result}: iteration {k} played{played} at {rate:g} Hz")
    robot = excitation.robot
    tau = np.array([robot.torques(*x) for x in zip(q, qd, qdd)])
    needed = approach_duration(excitation)
    approach = needed if approach is None else float(approach)
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
        )
        + _slipping(stance)
        + _unsupported(robot, stance),
        held=stance,
        approach=approach,
        approach_needed=needed,
        reach=approach_shortfall(excitation, approach),
    )


def _unsupported(robot, stance: HeldTorques | None) -> tuple[str, ...]:
    """A line when a floating-base robot is exported without its held joints' feed-forward: its problem
    names no soles to stand on (:func:`~excite_cli.design.held_joints.held_joints`)."""
    if stance is not None or not has_floating_base(robot):
        return ()
    return (
        "constraints.zmp.support_links: the robot has a floating base but its problem names no soles "
        "(constraints.zmp or constraints.com support_links): the export gives the active joints' torques with the "
        "base at rest, not the held joints' feed-forward that keeps it standing",
    )


def fastest_passing(playback: Playback, constraints: list[Constraint], rate: float, speed: float) -> float | None:
    """The largest speed in [1, ``speed``) (times the optimized, to ``SPEED_STEP``) whose samples at
    ``rate`` [Hz] keep ``constraints``, found by bisection (velocities scale with the speed, accelerations
    with its square, torques and the zero-moment point with neither alone); None where ``speed`` ≤ 1 or
    the optimized speed itself does not pass."""

    def passes(s: float) -> bool:
        return check_motion(constraints, *playback.sample(rate, speed=s))[0] <= 0.0

    if speed <= 1.0 or not passes(1.0):
        return None
    lo, hi = 1.0, speed
    while hi - lo > SPEED_STEP:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if passes(mid) else (lo, mid)
    return float(np.floor(lo / SPEED_STEP + 1e-9) * SPEED_STEP)


def _check_held_efforts(stance: HeldTorques, what: str) -> None:
    """Refuse held-joint torques above their URDF effort limits (where the URDF gives one).

    Raises:
        ExciteError: (``result``) the joint of the largest excess, its torque and limit.
    """
    limited = np.isfinite(stance.effort) & (stance.effort > 0)
    excess = np.where(limited, np.abs(stance.tau).max(axis=0) - stance.effort, -np.inf)
    if excess.max() > 0.0:
        j = int(np.argmax(excess))
        raise ExciteError(
            "result",
            f"{what} needs {np.abs(stance.tau[:, j]).max():.1f} Nm of the held joint '{stance.joint_names[j]}' "
            f"to keep the robot still, above its URDF effort limit of {stance.effort[j]:g} Nm; no file written",
        )


def _slipping(stance: HeldTorques | None) -> tuple[str, ...]:
    """The warning for samples whose ground wrench no contact forces inside the friction cones give."""
    if stance is None or not stance.slipping:
        return ()
    return (
        f"held joints: at {stance.slipping} samples no contact forces inside the soles' friction cones "
        "hold the robot still (it may tip or slip); their feed-forward takes the least-norm forces",
    )
