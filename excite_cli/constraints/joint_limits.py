"""Joint position, velocity and acceleration limits x_min ≤ x(t) ≤ x_max (Eq. 51).

Sampled on the paper's 0.02 s grid these are T × n × 3 × 2 linear inequalities (tens of thousands),
which makes SLSQP crawl. Each (order, side, joint) is aggregated instead into one smooth inequality:
with s_t = (x_t − x_max)/h (or (x_min − x_t)/h), h the half-width of the allowed range,

    g = (1/β) log Σ_t exp(β s_t) + δ ≤ 0      (see ``lse.py``),

so SLSQP sees 6n inequalities. The final trajectory is re-checked exactly on a finer grid.
"""

from __future__ import annotations

import warnings

import numpy as np

from excite_cli.config import LimitsConfig, PerJoint
from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.constraints.lse import ACCEPT_MARGIN, GRID_MARGIN, smooth_max
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError, ExciteWarning
from excite_cli.trajectory.fourier import FourierBasis

ORDERS = ("position_rad", "velocity_rad_s", "acceleration_rad_s2")


class JointLimits(Constraint):
    """Eq. 51 on the constraint grid, 6n aggregated inequalities.

    Args:
        lower, upper: (3, n) bounds of q [rad], q̇ [rad/s], q̈ [rad/s²].
        basis: Fourier basis on the constraint grid.
        names: (n,) the joints, as the messages name them (default: joint 1 … n).

    Raises:
        ValueError: a lower bound is not below its upper bound.
    """

    name = "joint_limits"
    field = "robot.home_posture"  # the limits come from the URDF; what violates them is the home posture
    grid_margin = ACCEPT_MARGIN

    def __init__(self, lower: np.ndarray, upper: np.ndarray, basis: FourierBasis, names: list[str] | None = None):
        self.lower = np.asarray(lower, dtype=float)
        self.names = list(names) if names is not None else [f"joint {j + 1}" for j in range(self.lower.shape[1])]
        self.upper = np.asarray(upper, dtype=float)
        if np.any(self.upper <= self.lower):
            raise ValueError("joint limits: an upper bound is not above its lower bound")
        self.half = (self.upper - self.lower) / 2.0
        self.centre = (self.upper + self.lower) / 2.0
        self.basis = basis
        self._orders = (basis.q, basis.qd, basis.qdd)

    def in_words(self) -> str:
        """The rows, in words (for ``check``)."""
        return f"position, velocity, acceleration × lower, upper × {self.lower.shape[1]} joints"

    def _normalized(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """(3, T, n) samples q, q̇, q̈ (T, n) scaled so that ±1 is a bound and 0 the centre."""
        return np.stack([(x - self.centre[d]) / self.half[d] for d, x in enumerate((q, qd, qdd))])

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """6n aggregated values (order × side × joint) and their Jacobian (6n, α.size)."""
        n, m = alpha.shape
        z = self._normalized(*(B @ alpha.T for B in self._orders))
        s = np.concatenate([z - 1.0, -z - 1.0])  # (6, T, n): upper sides, then lower sides
        g, w = smooth_max(s, axis=1)  # (6, n), (6, T, n)
        J = np.zeros((6, n, n, m))
        idx = np.arange(n)
        for k in range(6):
            d, sign = k % 3, (1.0 if k < 3 else -1.0)
            J[k, idx, idx, :] = sign * (w[k].T @ self._orders[d]) / self.half[d][:, None]
        return g.ravel(), J.reshape(6 * n, n * m)

    def check_samples(self, time: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> FineCheck:
        """Largest violation per order in rad, rad/s, rad/s² and normalized by the half-ranges."""
        z = self._normalized(q, qd, qdd)
        normalized = np.abs(z).max(axis=1) - 1.0  # (3, n)
        details = {}
        for d, order in enumerate(ORDERS):
            x = z[d] * self.half[d] + self.centre[d]
            details[f"max_violation_{order}"] = float(np.max(np.maximum(x - self.upper[d], self.lower[d] - x)))
        d, j = np.unravel_index(np.argmax(normalized), normalized.shape)
        where = f"{ORDERS[d].split('_')[0]} of {self.names[j]} at {normalized[d, j] + 1:.3f} of its half-range"
        return FineCheck(max_violation=float(normalized.max()), details=details, where=where)

    def coefficient_scale(self) -> np.ndarray:
        """(n, 2N+1) per-coefficient scale [rad]: the change of a coefficient that moves its joint's
        normalized q, q̇ or q̈ by at most 1 on the grid. A diagonal preconditioner for the optimizer:
        without it the k-th harmonic weighs (kω)² more in q̈ than the first."""
        effect = np.stack([np.abs(B).max(axis=0)[None, :] / self.half[d][:, None] for d, B in enumerate(self._orders)])
        return 1.0 / effect.max(axis=0)

    def restore(self, alpha: np.ndarray) -> np.ndarray:
        """Scale each joint's oscillation about its offset q0 (clamped into the range) so that its
        samples stay 1 − δ inside every bound on the grid: the smallest change of shape that makes a
        slightly violating SQP iterate feasible. α (n, 2N+1) in, same shape out."""
        inner = 1.0 - GRID_MARGIN
        out = alpha.copy()
        out[:, 0] = np.clip(out[:, 0], self.centre[0] - inner * self.half[0], self.centre[0] + inner * self.half[0])
        offset = (out[:, 0] - self.centre[0]) / self.half[0]  # (n,)
        wave = out.copy()
        wave[:, 0] = 0.0
        scale = np.ones(out.shape[0])
        for d, B in enumerate(self._orders):
            o = (B @ wave.T) / self.half[d]  # (T, n) normalized oscillation
            z0 = offset if d == 0 else np.zeros_like(offset)
            with np.errstate(divide="ignore", invalid="ignore"):
                room = np.where(o > 0, (inner - z0) / o, np.where(o < 0, (inner + z0) / -o, np.inf))
            scale = np.minimum(scale, room.min(axis=0))
        out[:, 1:] *= np.clip(scale, 0.0, 1.0)[:, None]
        return out

    def random_start(
        self,
        coefficients: int,
        rng: np.random.Generator,
        fill: float,
        offset: np.ndarray | None = None,
        wave_space: np.ndarray | None = None,
    ) -> np.ndarray:
        """Random α (n, coefficients) oscillating about ``offset`` (n,) [rad] (default: the centre of
        each position range), scaled so that each joint uses the fraction ``fill`` of its room on the
        grid in position, velocity and acceleration (fill < 1: strictly feasible). With
        ``wave_space`` (coefficients − 1, r), an orthonormal basis, the oscillations are drawn in it
        (see :attr:`BoundaryConditions.wave_space`: rest at both ends).

        Raises:
            ValueError: ``fill`` not in (0, 1), or ``offset`` outside the position bounds.
        """
        if not 0.0 < fill < 1.0:
            raise ValueError("fill must be in (0, 1)")
        offset = self.centre[0] if offset is None else np.asarray(offset, dtype=float)
        z0 = (offset - self.centre[0]) / self.half[0]
        if np.any(np.abs(z0) >= 1.0):
            raise ValueError("offset outside the position bounds")
        n = self.lower.shape[1]
        harmonics = (coefficients - 1) // 2
        decay = 1.0 / np.tile(np.arange(1, harmonics + 1), 2)
        alpha = np.zeros((n, coefficients))
        alpha[:, 1:] = rng.standard_normal((n, coefficients - 1)) * decay
        if wave_space is not None:
            alpha[:, 1:] = alpha[:, 1:] @ wave_space @ wave_space.T
        room = np.stack([1.0 - np.abs(z0), np.ones(n), np.ones(n)])
        peak = np.stack([np.abs(B @ alpha.T).max(axis=0) / self.half[d] for d, B in enumerate(self._orders)])
        alpha[:, 1:] *= (fill * (room / peak).min(axis=0))[:, None]
        alpha[:, 0] = offset
        return alpha


def per_joint(
    field: str,
    value: PerJoint | None,
    default: np.ndarray,
    robot: Robot,
    zero_allowed: bool = False,
    noun: str | None = None,
) -> np.ndarray:
    """(n,) positive limits of the config field ``field`` from a scalar, a {joint: value} map (the
    others from ``default``) or None (all from ``default``); with ``zero_allowed``, ≥ 0 (a margin).
    ``noun`` names the value in the messages (default: limit, or margin with ``zero_allowed``).

    Raises:
        ExciteError: an unknown joint, or a joint left without a positive (or, with ``zero_allowed``,
            non-negative) finite value.
    """
    out = default.astype(float).copy()
    if isinstance(value, dict):
        for name, v in value.items():
            if name not in robot.joint_names:
                raise ExciteError(field, f"'{name}' is not an active joint")
            out[robot.joint_names.index(name)] = v
    elif value is not None:
        out[:] = value
    given = value if isinstance(value, dict) else {}
    for name, v in zip(robot.joint_names, out):
        if not np.isfinite(v) or v < 0 or (v == 0 and not zero_allowed):
            if value is None or (given and name not in given and np.isnan(v)):
                source = "the robot's file has none" if value is None else "none given for it, and no default"
            else:
                source = f"got {v:g}"
            noun = noun or ("margin" if zero_allowed else "limit")
            kind = f"non-negative finite {noun}" if zero_allowed else f"positive finite {noun}"
            expected = f"{field}: {{{name}: value}}"
            raise ExciteError(field, f"joint '{name}' needs a {kind} ({source})", expected=expected)
    return out


#: A configured velocity limit this many times the URDF's or more is warned about: the joint cannot
#: move that fast, so the number is likely in another unit (deg/s is 57.3 times rad/s: a limit meant as
#: 0.2-1 times the URDF's in deg/s reads as 11-57 times it, which the warning names).
BEYOND_URDF = 3.0


def _beyond_the_urdf(velocity: np.ndarray, robot: Robot) -> None:
    """Warn (:class:`~excite_cli.errors.ExciteWarning`) of each configured velocity limit (n,) [rad/s,
    m/s for a prismatic joint] ``BEYOND_URDF`` times the URDF's or more, naming the joint, both values
    and the likely unit."""
    for name, given, urdf in zip(robot.joint_names, velocity, robot.velocity_limit):
        if 0.0 < urdf < np.inf and given >= BEYOND_URDF * urdf:
            kind = robot.model.joints[robot.model.getJointId(name)].shortname().removeprefix("JointModel")
            unit = "m/s" if kind.startswith("P") else "rad/s"  # a prismatic joint's limit is a speed
            hint = " (deg/s? limits are in rad/s)" if unit == "rad/s" and 10.0 <= given / urdf <= 100.0 else ""
            warnings.warn(
                f"limits.velocity: {given:g} {unit} for joint '{name}' is {given / urdf:.3g} times the URDF's "
                f"{urdf:g} {unit}{hint}",
                ExciteWarning,
            )


def joint_limit_bounds(cfg: LimitsConfig, robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """Bounds (lower, upper), each (3, n), of q [rad], q̇ [rad/s], q̈ [rad/s²] for Eq. 51.

    Position: the URDF limits tightened by ``position_margin`` (one value, or per joint). Velocity: the
    config, else the URDF. Acceleration: the config (URDFs have none).

    Raises:
        ExciteError: a missing or non-positive limit, an unknown joint, a negative margin or one that
            leaves no range.
    """
    field = "limits.position_margin"
    margin = per_joint(field, cfg.position_margin, np.zeros(robot.n_joints), robot, zero_allowed=True)
    lower, upper = robot.lower + margin, robot.upper - margin
    for name, lo, hi, m in zip(robot.joint_names, lower, upper, margin):
        if not (np.isfinite(lo) and np.isfinite(hi)):
            raise ExciteError(
                "robot.joint_ranges",
                f"joint '{name}' has no range in the robot's file (continuous, or an MJCF joint without range)",
                name,
                f"robot.joint_ranges: {{{name}: [lower, upper]}}, the range [rad or m] it may move in",
            )
        if hi <= lo:
            raise ExciteError(field, f"{m:g} rad leaves no range for joint '{name}'")
    velocity = per_joint("limits.velocity", cfg.velocity, robot.velocity_limit, robot)
    if cfg.velocity is not None:
        _beyond_the_urdf(velocity, robot)
    acceleration = per_joint("limits.acceleration", cfg.acceleration, np.full(robot.n_joints, np.nan), robot)
    return np.stack([lower, -velocity, -acceleration]), np.stack([upper, velocity, acceleration])
