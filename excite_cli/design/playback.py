"""What a robot plays: from the home posture at rest into the optimized trajectory, P periods of it,
and back to the home posture at rest, sampled at the controller's rate.

The pieces are joined by quintic polynomials, which match position, velocity and acceleration at
both ends (so the played motion is C² everywhere). With s = t/D ∈ [0, 1] and the end states
(q₀, q̇₀, q̈₀), (q₁, q̇₁, q̈₁), per joint

    p(s) = c₀ + c₁s + c₂s² + c₃s³ + c₄s⁴ + c₅s⁵,  c₀ = q₀, c₁ = Dq̇₀, c₂ = D²q̈₀/2,
    c₃ = 10h − 4e + f/2,  c₄ = −15h + 7e − f,  c₅ = 6h − 3e + f/2,

with h = q₁ − (c₀ + c₁ + c₂), e = Dq̇₁ − (c₁ + 2c₂), f = D²q̈₁ − 2c₂ (Hermite interpolation). Rest to
rest it is the minimum-jerk profile, peak speed 15Δ/(8D) and peak acceleration 10Δ/(√3 D²); D is the
shortest multiple of ``RESOLUTION`` for which every sample keeps the joint limits (Eq. 51) and what a
slower motion keeps better, where the problem has it: the torque limits and a standing robot's
zero-moment point (a humanoid's arms brought to the trajectory's start in 0.68 s tipped it; slower, the
ZMP stays where standing still puts it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, Sequence

import numpy as np

from excite_cli.constraints import Constraint, JointLimits
from excite_cli.constraints.lse import ACCEPT_MARGIN, GRID_MARGIN
from excite_cli.design.excitation import Excitation
from excite_cli.errors import ExciteError
from excite_cli.trajectory.fourier import FourierTrajectory

#: Transition durations are multiples of this [s], so that they are the same at every common rate.
RESOLUTION = 0.01
#: Samples per transition when its limits are checked during planning.
PLANNING_SAMPLES = 400
#: End states closer than this (rad, rad/s, rad/s²) are joined without a transition.
SAME_STATE = 1e-9
#: Longest transition tried [s].
LONGEST = 120.0


class Segment(Protocol):
    """A piece of played motion: ``name``, ``duration`` [s] and ``evaluate(t)`` → q, q̇, q̈ (T, n)."""

    name: str
    duration: float

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


@dataclass(frozen=True)
class FourierSegment:
    """One period of the optimized trajectory α (n, 2N+1) over [0, ``duration``] [s] (Eq. 50)."""

    trajectory: FourierTrajectory
    alpha: np.ndarray
    duration: float
    name: str = "trajectory"

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, q̇, q̈ (T, n) [rad, rad/s, rad/s²] at local times ``t`` (T,) [s]."""
        return self.trajectory.basis(t).evaluate(self.alpha)

    def state(self, t: float) -> np.ndarray:
        """(3, n) q, q̇, q̈ at the local time ``t`` [s]."""
        return np.stack([x[0] for x in self.evaluate(np.array([t]))])


@dataclass(frozen=True)
class Transition:
    """Quintic from the state ``start`` to ``end`` (each (3, n): q, q̇, q̈) in ``duration`` [s]."""

    start: np.ndarray
    end: np.ndarray
    duration: float
    name: str = "transition"

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, q̇, q̈ (T, n) at local times ``t`` (T,) [s], clamped to [0, duration]."""
        D = self.duration
        (q0, v0, a0), (q1, v1, a1) = self.start, self.end
        c0, c1, c2 = q0, D * v0, D**2 * a0 / 2.0
        h, e, f = q1 - (c0 + c1 + c2), D * v1 - (c1 + 2.0 * c2), D**2 * a1 - 2.0 * c2
        c = np.stack([c0, c1, c2, 10 * h - 4 * e + f / 2, -15 * h + 7 * e - f, 6 * h - 3 * e + f / 2])  # (6, n)
        s = np.clip(np.asarray(t, dtype=float) / D, 0.0, 1.0)[:, None]
        k = np.arange(6)
        q = (s**k) @ c
        qd = (k * s ** np.maximum(k - 1, 0)) @ c / D
        qdd = (k * (k - 1) * s ** np.maximum(k - 2, 0)) @ c / D**2
        return q, qd, qdd


def approach_duration(excitation: Excitation) -> float:
    """[s] How long a controller takes to bring the robot from wherever it stands in its joint range
    (the robot's file's) to the home posture at rest without exceeding the problem's velocity and
    acceleration limits, on the quintic a joint_trajectory_controller interpolates from its current
    state to a point with positions, velocities and accelerations (its spline interpolation): the
    rest-to-rest bound max_j(15 Δ_j / (8 v_j), (10 Δ_j / (√3 a_j))^½) with Δ_j the farthest joint j
    can stand from home, rounded up to ``RESOLUTION``."""
    delta, (velocity, acceleration) = _farthest(excitation), _rest_limits(excitation)
    bound = max(
        float(np.max(15.0 * delta / (8.0 * velocity))),
        float(np.max(np.sqrt(10.0 * delta / (np.sqrt(3.0) * acceleration)))),
    )
    return round(float(np.ceil(bound / RESOLUTION - 1e-9) * RESOLUTION), 6)


def approach_reach(excitation: Excitation, duration: float) -> np.ndarray:
    """(n,) [rad] How far from home each joint can start and still be brought there at rest in
    ``duration`` [s] within the problem's velocity and acceleration limits, on the same quintic as
    :func:`approach_duration` (its bound solved for Δ: min(8 v T / 15, √3 a T² / 10))."""
    velocity, acceleration = _rest_limits(excitation)
    return np.minimum(8.0 * velocity * duration / 15.0, np.sqrt(3.0) * acceleration * duration**2 / 10.0)


def approach_shortfall(excitation: Excitation, duration: float) -> tuple[tuple[str, float], ...]:
    """(joint, reach [rad]) of the joints that ``duration`` [s] brings home only from within their
    :func:`approach_reach`, nearer than the farthest they can stand (:func:`approach_duration`'s Δ);
    empty from :func:`approach_duration` on."""
    if duration >= approach_duration(excitation):
        return ()
    reach = approach_reach(excitation, duration)
    names = excitation.robot.joint_names
    return tuple((name, float(d)) for name, d, far in zip(names, reach, _farthest(excitation)) if d < far)


def _farthest(excitation: Excitation) -> np.ndarray:
    """(n,) [rad] The farthest each joint can stand from home: in the robot's file's range, or in the
    problem's position limits for a joint without one."""
    robot, limits = excitation.robot, excitation.limits
    delta = np.maximum(robot.upper - robot.home, robot.home - robot.lower)
    within = np.maximum(limits.upper[0] - robot.home, robot.home - limits.lower[0])  # a joint without a range
    return np.where(np.isfinite(delta), delta, within)


def _rest_limits(excitation: Excitation) -> tuple[np.ndarray, np.ndarray]:
    """(n,) each: the problem's velocity [rad/s] and acceleration [rad/s²] limits, the smaller side."""
    limits = excitation.limits
    return np.minimum(-limits.lower[1], limits.upper[1]), np.minimum(-limits.lower[2], limits.upper[2])


def plan_transition(
    start: np.ndarray, end: np.ndarray, limits: JointLimits, name: str, slowed: Sequence[Constraint] = ()
) -> Transition | None:
    """The shortest quintic from ``start`` to ``end`` ((3, n) states) whose samples keep the joint
    limits and every constraint of ``slowed`` (those a slower motion keeps better: torque limits, the
    zero-moment point) with the optimizer's acceptance margin; None when the states are the same.
    When no duration keeps ``slowed`` (gravity alone exceeds a torque limit on the way), the shortest
    that keeps the joint limits.

    The search starts at the rest-to-rest bound max_j(15|Δ_j|/(8 v_j), (10|Δ_j|/(√3 a_j))^½) with
    the limits tightened by the grid margin, and lengthens by 10 % steps.

    Raises:
        ExciteError: no duration up to ``LONGEST`` keeps the joint limits (only possible when an end
            is not at rest).
    """
    if np.abs(end - start).max() <= SAME_STATE:
        return None
    inner = 1.0 - GRID_MARGIN
    delta = np.abs(end[0] - start[0])
    velocity = inner * np.minimum(-limits.lower[1], limits.upper[1])
    acceleration = inner * np.minimum(-limits.lower[2], limits.upper[2])
    shortest = max(
        float(np.max(15.0 * delta / (8.0 * velocity))),
        float(np.sqrt(np.max(10.0 * delta / (np.sqrt(3.0) * acceleration)))),
        RESOLUTION,
    )
    duration, within_limits = shortest, None
    while duration <= LONGEST:
        transition = Transition(start, end, float(np.ceil(duration / RESOLUTION - 1e-9) * RESOLUTION), name)
        t = np.linspace(0.0, transition.duration, PLANNING_SAMPLES)
        samples = transition.evaluate(t)
        if limits.check_samples(t, *samples).max_violation <= -ACCEPT_MARGIN / 2:
            if all(c.check_samples(t, *samples).max_violation <= -ACCEPT_MARGIN / 2 for c in slowed):
                return transition
            within_limits = within_limits or transition
        duration *= 1.1
    if within_limits is not None:
        return within_limits
    raise ExciteError(name, f"no quintic of up to {LONGEST:g} s keeps the joint limits")


@dataclass(frozen=True)
class Playback:
    """Segments played one after the other (transitions and periods of the trajectory)."""

    segments: tuple[Segment, ...]

    @property
    def duration(self) -> float:
        """Total duration [s]."""
        return float(sum(s.duration for s in self.segments))

    def sample(
        self, rate: float, only: Sequence[str] | None = None, speed: float = 1.0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """time (S,) [s] = k / ``rate`` [Hz] up to the first instant at or after the end (held at the
        final state there), and q, q̇, q̈ (S, n); with ``only``, just the samples of segments with
        those names. At ``speed`` s ≠ 1 the motion is played s times faster: q_s(t) = q(s t), so
        q̇ scales by s and q̈ by s² (what the joints, the torques and the zero-moment point see)."""
        if speed != 1.0:
            time, q, qd, qdd = self.sample(rate / speed, only)
            return np.round(time * rate / speed) / rate, q, speed * qd, speed**2 * qdd
        count = int(np.ceil(self.duration * rate - 1e-6)) + 1
        time = np.arange(count) / rate
        starts = np.cumsum([0.0] + [s.duration for s in self.segments])
        which = np.clip(np.searchsorted(starts, time, side="right") - 1, 0, len(self.segments) - 1)
        n = self.segments[0].evaluate(np.zeros(1))[0].shape[1]
        out = np.zeros((3, count, n))
        for i, segment in enumerate(self.segments):
            mask = which == i
            if mask.any():
                out[:, mask] = np.stack(segment.evaluate(np.minimum(time[mask] - starts[i], segment.duration)))
        keep = np.isin([self.segments[i].name for i in which], only) if only is not None else np.ones(count, bool)
        return time[keep], out[0][keep], out[1][keep], out[2][keep]


def plan_playback(excitation: Excitation, alpha: np.ndarray, periods: int = 1) -> Playback:
    """Home posture at rest → q(0), ``periods`` periods of α (n, 2N+1) (joined where q(T) ≠ q(0) or the
    velocities differ), q(T) → home at rest.

    Raises:
        ExciteError: ``periods`` < 1, or a transition cannot keep the joint limits.
    """
    if periods < 1:
        raise ExciteError("periods", f"{periods} is out of range", periods, "at least 1")
    home = np.stack([excitation.home, np.zeros_like(excitation.home), np.zeros_like(excitation.home)])
    trajectory = FourierSegment(excitation.trajectory, alpha, excitation.spec.trajectory.duration)
    first, last = trajectory.state(0.0), trajectory.state(trajectory.duration)
    limits = excitation.limits
    slowed = [c for c in excitation.constraints if c.eased_by_slowing]
    pieces: list[Segment | None] = [plan_transition(home, first, limits, "transition in", slowed)]
    for p in range(periods):
        pieces.append(trajectory)
        if p < periods - 1:
            pieces.append(plan_transition(last, first, limits, "link", slowed))
    pieces.append(plan_transition(last, home, limits, "transition out", slowed))
    return Playback(tuple(s for s in pieces if s is not None))


def check_motion(
    constraints: Sequence[Constraint], time: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray
) -> tuple[float, str]:
    """Largest normalized violation of every constraint on sampled motion (≤ 0: satisfied) and where
    the worst one is, in words. ``time`` (T,) [s], q, q̇, q̈ (T, n)."""
    if time.size == 0:
        return -np.inf, ""
    checks = [(c.name, c.check_samples(time, q, qd, qdd)) for c in constraints]
    name, worst = max(checks, key=lambda item: item[1].max_violation)
    return worst.max_violation, f"{name}: {worst.where}" if worst.where else name
