"""Self-collision between capsules (Eq. 53): the distance between each capsule pair stays above a
safety margin over the constraint grid.

In the optimizer, the joint placements at all grid instants come at once
(:class:`~excite_cli.dynamics.kinematics.BatchKinematics`), then each capsule's segment, and every
(instant, pair) distance d = |c₂ − c₁| − r₁ − r₂ in one compiled loop (:mod:`excite_cli.collision.segments`,
Ericson's closed form). Per pair, s_t = (margin − d_t) / L with L = ``LENGTH_SCALE`` is aggregated
by a log-sum-exp over the grid; it varies as ∂d = nᵀ(J_{c₂} − J_{c₁}) ∂q, J_c the velocity Jacobian
of the closest point fixed to its body. coal (the reference, equal to the closed form to 1e-15)
gives the distance of the exact checks: the fine check asks coal at every sample the closed form
puts within ``CONFIRM`` of the smallest distance.
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

import excite_cli.constraints.lse as lse
from excite_cli.collision.capsules import Capsule, capsule_frames, segment_ends
from excite_cli.collision.segments import CapsulePairs, pair_aggregates, pair_distances, pair_jacobian
from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.dynamics.kinematics import BatchKinematics
from excite_cli.dynamics.robot import Robot
from excite_cli.memo import once
from excite_cli.trajectory.fourier import FourierBasis

#: Distances are normalized by this length [m].
LENGTH_SCALE = 0.05
#: The fine check asks coal for every sample screened within this of the smallest distance [m].
CONFIRM = 1e-3


def _point_segment(point: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    """Distance [m] from ``point`` (3,) to the segment [start, end]."""
    along = end - start
    t = np.clip((point - start) @ along / max(along @ along, 1e-300), 0.0, 1.0)
    return float(np.linalg.norm(point - start - t * along))


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
    grid_margin = lse.ACCEPT_MARGIN

    def __init__(
        self, robot: Robot, basis: FourierBasis, capsules: list[Capsule], pairs: list[tuple[int, int]], margin: float
    ):
        self.robot, self.basis, self.capsules, self.pairs, self.margin = robot, basis, capsules, pairs, margin
        self._shapes = [coal.Capsule(c.radius, float(np.linalg.norm(c.end - c.start))) for c in capsules]
        first, second = np.array([i for i, _ in pairs], dtype=int), np.array([j for _, j in pairs], dtype=int)
        radii, margins = np.array([c.radius for c in capsules]), np.full(len(pairs), margin)
        self._pairs = CapsulePairs(first, second, radii, margins, LENGTH_SCALE, lse.SHARPNESS)
        joints = np.array([c.joint for c in capsules], dtype=int)
        self.kinematics = BatchKinematics(robot)
        ancestors = self.kinematics.ancestors
        # (P, n): +1 where an active joint moves only the second capsule, −1 only the first
        self._moves = ancestors[joints[second]].astype(float) - ancestors[joints[first]]

    def in_words(self) -> str:
        """The rows, in words (for ``check``)."""
        links = {frozenset((self.capsules[i].link, self.capsules[j].link)) for i, j in self.pairs}
        return f"one per capsule pair ({len(self.pairs)}, of {len(links)} link pairs)"

    def never_apart(self, Q: np.ndarray, apart: float) -> list[tuple[tuple[str, str], float]]:
        """Link pairs never more than ``apart`` [m] apart at the postures Q (K, n), with the largest distance."""
        if not self.pairs:
            return []
        d = self.distances(Q).max(axis=0)
        return [
            ((self.capsules[i].link, self.capsules[j].link), float(d[k]))
            for k, (i, j) in enumerate(self.pairs)
            if d[k] < apart
        ]

    def out_of_reach(self) -> list[tuple[tuple[str, str], float]]:
        """Link pairs whose capsules no motion of the active joints brings within the margin, with the
        smallest distance [m] they could have (a bound, not a sample): every point of a capsule lies within
        its reach of the origin of the first active joint that moves it (the offsets between the joints
        of the chain summed, plus the capsule's farthest end from its joint and its radius), and a capsule no
        active joint moves stays where it is (the triangle inequality)."""
        model, data = self.robot.model, self.robot.model.createData()
        pin.forwardKinematics(model, data, self.robot.q_reference)
        active = {model.getJointId(name) for name in self.robot.joint_names}
        where = []
        for c in self.capsules:
            chain = [j for j in model.supports[c.joint].tolist() if j in active]
            far = max(np.linalg.norm(c.start), np.linalg.norm(c.end)) + c.radius
            offsets = sum(np.linalg.norm(model.jointPlacements[j].translation) for j in chain[1:])
            if chain:
                where.append((chain[0], data.oMi[chain[0]].translation.copy(), offsets + far))
            else:
                placement = data.oMi[c.joint]
                ends = [placement.act(np.asarray(e, float)) for e in (c.start, c.end)]
                where.append((None, ends, c.radius))
        found = []
        for i, j in self.pairs:
            (first_i, at_i, reach_i), (first_j, at_j, reach_j) = where[i], where[j]
            if first_i is not None and first_j is not None:
                gap = np.inf if first_i == first_j else np.linalg.norm(at_i - at_j) - reach_i - reach_j
            elif first_i is None and first_j is None:
                continue
            else:
                (origin, reach), (ends, radius) = (
                    ((at_i, reach_i), (at_j, reach_j)) if first_i is not None else ((at_j, reach_j), (at_i, reach_i))
                )
                gap = _point_segment(origin, *ends) - radius - reach
            if np.isfinite(gap) and gap > self.margin:
                found.append(((self.capsules[i].link, self.capsules[j].link), float(gap)))
        return found

    def drawn(self) -> dict[str, object]:
        """The margin under the closest capsule distance's track."""
        return {"margin": self.margin}

    def clearance(self, Q: np.ndarray) -> np.ndarray:
        """(K,) the smallest distance [m] beyond the margin over every pair at the postures Q (K, n)."""
        return (self.distances(Q) - self.margin).min(axis=1, initial=np.inf)

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
        """Distances (T, P) [m] of every kept capsule pair at the configurations Q (T, n) (closed form)."""
        start, end = self._ends(Q)[:2]
        return pair_distances(start, end, self._pairs)

    def _ends(self, Q: np.ndarray) -> tuple[np.ndarray, ...]:
        """At the configurations Q (T, n): every capsule's segment ends (3, T, C) [m] and the joint
        placements (:func:`~excite_cli.collision.capsules.segment_ends`)."""
        return once(self, "ends", Q, lambda: segment_ends(self.kinematics, self.capsules, Q))

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One aggregated value per pair (P,) and the Jacobian (P, α.size), see :meth:`Constraint.evaluate`
        (:func:`~excite_cli.collision.segments.pair_jacobian`)."""
        n, m = alpha.shape
        if not self.pairs:
            return np.zeros(0), np.zeros((0, n * m))
        start, end, R, p = self._ends(self.basis.q @ alpha.T)
        axes, moments = self.kinematics.joint_axes(R, p)
        g, J = pair_jacobian(
            start, end, self._pairs, axes, moments, self.kinematics.revolute, self._moves, self.basis.q
        )
        return g + lse.GRID_MARGIN, J.reshape(len(self.pairs), n * m)

    def values(self, alpha: np.ndarray) -> np.ndarray:
        """The aggregated values of :meth:`evaluate` (P,) without the Jacobian."""
        if not self.pairs:
            return np.zeros(0)
        return pair_aggregates(*self._ends(self.basis.q @ alpha.T)[:2], self._pairs) + lse.GRID_MARGIN

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
