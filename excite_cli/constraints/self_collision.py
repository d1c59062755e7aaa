"""Self-collision between capsules (Eq. 53): the distance between each capsule pair stays above a
safety margin over the constraint grid.

In the optimizer, every (instant, pair) distance is computed at once in vectorized numpy: the joint
placements at all grid instants (:class:`~excite_cli.dynamics.kinematics.BatchKinematics`), each capsule's
segment, and the closest points of the two segments in closed form (``segment_parameters``);
the capsule distance is d = |c₂ − c₁| − r₁ − r₂ with normal n = (c₂ − c₁)/|c₂ − c₁|. It varies as
∂d = nᵀ(J_{c₂} − J_{c₁}) ∂q, J_c the velocity Jacobian of the closest point fixed to its body
(``BatchKinematics.distance_rates``). Per pair, s_t = (margin − d_t) / L with L = ``LENGTH_SCALE``
is aggregated by a log-sum-exp over the grid. coal (the reference, equal to the closed form to
1e-15) gives the distance of the exact checks: the fine check asks coal at every sample the closed
form puts within ``CONFIRM`` of the smallest distance.
"""

from __future__ import annotations

import coal
import numpy as np

from excite_cli.collision.capsules import Capsule, capsule_frames, segment_ends, segment_parameters
from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.constraints.lse import ACCEPT_MARGIN, smooth_max, smooth_max_value
from excite_cli.dynamics.kinematics import BatchKinematics
from excite_cli.dynamics.robot import Robot
from excite_cli.trajectory.fourier import FourierBasis

#: Distances are normalized by this length [m].
LENGTH_SCALE = 0.05
#: The fine check asks coal for every sample screened within this of the smallest distance [m].
CONFIRM = 1e-3
#: Instants screened at a time: a fine grid's (3, T, P) arrays at once outgrow the processor's caches.
BLOCK = 512


def aggregated_distances(
    kinematics: BatchKinematics,
    basis: FourierBasis,
    margin: float | np.ndarray,
    d: np.ndarray,
    points: np.ndarray,
    normals: np.ndarray,
    R: np.ndarray,
    p: np.ndarray,
    moves: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Per pair, s_t = (margin − d_t)/L aggregated over the grid instants by a log-sum-exp, and its
    Jacobian in α: ∂g/∂q(t) = Σ (∂g/∂d) nᵀJ_x, with ∂g/∂d = −w/L folded into the normals.

    Args:
        kinematics, basis: the constraint's batched kinematics and grid basis (T instants).
        margin: (P,) or scalar [m]; d: (T, P) distances [m].
        points, normals: (3, T, P) the point x whose motion changes d and the unit normal n along
            which it does (:meth:`BatchKinematics.distance_rates`); R, p: the joint placements.
        moves: (P, n) the sign with which each active joint moves the pair's distance (0: not at all).

    Returns:
        g (P,) and its Jacobian (P, α.size), α flattened row-major.
    """
    P, n = moves.shape
    m = basis.q.shape[1]
    g, w = smooth_max((margin - d) / LENGTH_SCALE, axis=0)  # (P,), (T, P)
    rates = kinematics.distance_rates(R, p, points, normals * (-w / LENGTH_SCALE))  # (T, P, n)
    J = (basis.q.T @ rates.reshape(d.shape[0], P * n)).reshape(m, P, n) * moves
    return g, J.transpose(1, 2, 0).reshape(P, n * m)


class SelfCollision(Constraint):
    """Eq. 53 on the constraint grid, one aggregated inequality per capsule pair.

    Args:
        robot: the robot.
        basis: Fourier basis on the constraint grid.
        capsules: the capsules.
        pairs: (i, j) indices of the pairs to keep apart.
        margin: safety distance [m] every pair keeps.
    """

    name = "self_collision"
    field = "constraints.self_collision"
    grid_margin = ACCEPT_MARGIN

    def __init__(
        self, robot: Robot, basis: FourierBasis, capsules: list[Capsule], pairs: list[tuple[int, int]], margin: float
    ):
        self.robot, self.basis, self.capsules, self.pairs, self.margin = robot, basis, capsules, pairs, margin
        self._shapes = [coal.Capsule(c.radius, float(np.linalg.norm(c.end - c.start))) for c in capsules]
        self._first = np.array([i for i, _ in pairs], dtype=int)
        self._second = np.array([j for _, j in pairs], dtype=int)
        self._radii = np.array([c.radius for c in capsules])
        self._joints = np.array([c.joint for c in capsules], dtype=int)
        self.kinematics = BatchKinematics(robot)
        ancestors = self.kinematics.ancestors
        # (P, n): +1 where an active joint moves only the second capsule, −1 only the first
        self._moves = ancestors[self._joints[self._second]].astype(float) - ancestors[self._joints[self._first]]

    def _distance(self, rotations: np.ndarray, centres: np.ndarray, t: int, p: int) -> coal.DistanceResult:
        """coal's distance of pair p at instant t, from capsule placements (T, C, 3, 3), (T, C, 3)."""
        i, j = self.pairs[p]
        result = coal.DistanceResult()
        coal.distance(
            self._shapes[i],
            coal.Transform3s(rotations[t, i], centres[t, i]),
            self._shapes[j],
            coal.Transform3s(rotations[t, j], centres[t, j]),
            coal.DistanceRequest(),
            result,
        )
        return result

    def distances(self, Q: np.ndarray) -> np.ndarray:
        """Distances (T, P) [m] of every kept capsule pair at the configurations Q (T, n) (closed form),
        ``BLOCK`` instants at a time."""
        if len(Q) <= BLOCK:
            return self._closest(Q)[0]
        return np.concatenate([self._closest_points(Q[k : k + BLOCK])[0] for k in range(0, len(Q), BLOCK)])

    def _closest(self, Q: np.ndarray) -> tuple[np.ndarray, ...]:
        """At the configurations Q (T, n): distances d (T, P) [m], the closest points c₁ (3, T, P) of
        each pair's first segment, the unit normals (3, T, P) from c₁ to c₂, and the joint placements
        (:meth:`BatchKinematics.placements`)."""
        key = Q.tobytes()  # the values and then the Jacobian at the same point: computed once
        if getattr(self, "_last_closest", (None,))[0] != key:
            self._last_closest = (key, self._closest_points(Q))
        return self._last_closest[1]

    def _closest_points(self, Q: np.ndarray) -> tuple[np.ndarray, ...]:
        """:meth:`_closest`, computed."""
        start, end, R, p = segment_ends(self.kinematics, self.capsules, Q)
        i, j = self._first, self._second
        d = end - start  # per capsule, then per pair: (3, T, C) before (3, T, P)
        squared = d[0] ** 2 + d[1] ** 2 + d[2] ** 2
        p1, p2, d1, d2 = start[..., i], start[..., j], d[..., i], d[..., j]
        s, t = segment_parameters(p1 - p2, d1, d2, squared[:, i], squared[:, j])
        c1 = p1 + s * d1
        gap = (p2 + t * d2) - c1
        length = np.sqrt(gap[0] ** 2 + gap[1] ** 2 + gap[2] ** 2)
        return length - self._radii[i] - self._radii[j], c1, gap / np.maximum(length, 1e-12), R, p

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One aggregated value per pair (P,) and the Jacobian (P, α.size), see :meth:`Constraint.evaluate`."""
        n, m = alpha.shape
        P = len(self.pairs)
        if not P:
            return np.zeros(0), np.zeros((0, n * m))
        return aggregated_distances(
            self.kinematics, self.basis, self.margin, *self._closest(self.basis.q @ alpha.T), self._moves
        )

    def values(self, alpha: np.ndarray) -> np.ndarray:
        """The aggregated values of :meth:`evaluate` (P,) without the Jacobian."""
        if not self.pairs:
            return np.zeros(0)
        return smooth_max_value((self.margin - self._closest(self.basis.q @ alpha.T)[0]) / LENGTH_SCALE, axis=0)

    track_units = {"min_capsule_distance": "m"}

    def track(self, alpha: np.ndarray, basis: FourierBasis) -> dict[str, np.ndarray]:
        """``min_capsule_distance``: (T,) smallest distance over the pairs at each instant [m]."""
        if not self.pairs:
            return {}
        return {"min_capsule_distance": self.distances(basis.q @ alpha.T).min(axis=1)}

    def check_samples(self, time: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> FineCheck:
        """Smallest distance over the postures q (T, n) and all pairs: the screen locates it, coal
        gives it (for every sample screened within ``CONFIRM`` of the smallest)."""
        if not self.pairs:
            return FineCheck(max_violation=-np.inf, details={}, where="no capsule pair")
        screened = self.distances(q)
        times, pairs = np.nonzero(screened <= screened.min() + CONFIRM)
        instants = np.unique(times)  # the placements of those instants alone
        rotations, centres = capsule_frames(*self.kinematics.placements(q[instants]), self.capsules)
        best, where = np.inf, (0, 0)
        for t, p in zip(times, pairs):
            d = self._distance(rotations, centres, int(np.searchsorted(instants, t)), p).min_distance
            if d < best:
                best, where = d, (t, p)
        i, j = self.pairs[where[1]]
        pair = f"{self.capsules[i].link}–{self.capsules[j].link}"
        return FineCheck(
            max_violation=(self.margin - best) / LENGTH_SCALE,
            details={
                "min_capsule_distance_m": float(best),
                "min_capsule_pair": pair,
                "min_capsule_time_s": float(time[where[0]]),
            },
            where=f"capsules {pair} {best * 100:.2f} cm apart (margin {self.margin * 100:.1f} cm)",
        )
