"""Self-collision between capsules (Eq. 53): the distance between each capsule pair stays above a
safety margin over the constraint grid.

Distances come from coal. With witness points p₁, p₂ and the normal n from capsule 1 to 2, the
signed distance varies as ∂d = nᵀ(J_{p₂} − J_{p₁}) ∂q, where J_p = J_v − [p − o]× J_ω is the
Jacobian of a point fixed to the body (o the body's joint origin, J in the world-aligned frame).
Per pair, s_t = (margin − d_t) / L with L = ``LENGTH_SCALE`` is aggregated by a log-sum-exp over the
grid. The distances of all (instant, pair) samples are first screened with a vectorized
segment-to-segment distance (``segment_distances``); coal then gives the exact distance, witness
points and normal of the samples within ``WINDOW`` of each pair's smallest screened distance, the
only ones whose log-sum-exp weight exceeds e^-30 of the largest. The fine re-check takes coal's
distance at the samples the screen finds within ``CONFIRM`` of the smallest.
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from excite_cli.capsules import Capsule, capsule_placements, segment_distances
from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.constraints.lse import ACCEPT_MARGIN, SHARPNESS, smooth_max
from excite_cli.robot import Robot
from excite_cli.trajectory import FourierBasis

#: Distances are normalized by this length [m].
LENGTH_SCALE = 0.05
#: Exact distances are computed up to this much above a pair's smallest one [m] (30 L / β).
WINDOW = 30.0 * LENGTH_SCALE / SHARPNESS
#: The fine check asks coal for every sample screened within this of the smallest distance [m].
CONFIRM = 1e-3
#: Samples whose aggregate weight is below this get no Jacobian.
WEIGHT_FLOOR = 1e-13


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
    grid_margin = ACCEPT_MARGIN

    def __init__(self, robot: Robot, basis: FourierBasis, capsules: list[Capsule], pairs: list[tuple[int, int]], margin: float):
        self.robot, self.basis, self.capsules, self.pairs, self.margin = robot, basis, capsules, pairs, margin
        self._shapes = [coal.Capsule(c.radius, float(np.linalg.norm(c.end - c.start))) for c in capsules]
        self._first = np.array([i for i, _ in pairs], dtype=int)
        self._second = np.array([j for _, j in pairs], dtype=int)


    def _distance(self, rotations: np.ndarray, centres: np.ndarray, t: int, p: int) -> coal.DistanceResult:
        i, j = self.pairs[p]
        result = coal.DistanceResult()
        coal.distance(self._shapes[i], coal.Transform3s(rotations[t, i], centres[t, i]),
                      self._shapes[j], coal.Transform3s(rotations[t, j], centres[t, j]), coal.DistanceRequest(), result)
        return result

    def _screen(self, rotations: np.ndarray, centres: np.ndarray) -> np.ndarray:
        """(T, P) capsule distances [m] from the segments' closest points."""
        half = np.array([s.halfLength for s in self._shapes])[None, :, None] * rotations[..., 2]
        start, end = centres - half, centres + half
        radii = np.array([c.radius for c in self.capsules])
        gap = segment_distances(start[:, self._first], end[:, self._first], start[:, self._second], end[:, self._second])
        return gap - radii[self._first] - radii[self._second]

    def _distances(self, rotations: np.ndarray, centres: np.ndarray) -> tuple[np.ndarray, dict[tuple[int, int], coal.DistanceResult]]:
        """(T, P) distances [m] and coal's results by (t, pair) near each pair's minimum."""
        d = self._screen(rotations, centres)
        near = d <= d.min(axis=0) + WINDOW
        exact = {}
        for t, p in zip(*np.nonzero(near)):
            exact[(t, p)] = self._distance(rotations, centres, t, p)
            d[t, p] = exact[(t, p)].min_distance
        return d, exact

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One aggregated value per pair (P,) and the Jacobian (P, α.size), see :meth:`Constraint.evaluate`."""
        n, m = alpha.shape
        if not self.pairs:
            return np.zeros(0), np.zeros((0, n * m))
        Q = self.basis.q @ alpha.T
        rotations, centres = capsule_placements(self.robot, self.capsules, Q)
        d, exact = self._distances(rotations, centres)
        g, w = smooth_max((self.margin - d) / LENGTH_SCALE, axis=0)  # (P,), (T, P)
        J = np.zeros((len(self.pairs), n, m))
        model, data = self.robot.model, self.robot.data
        for t in np.unique([t for (t, p) in exact if w[t, p] > WEIGHT_FLOOR]):
            pin.computeJointJacobians(model, data, self.robot.state(Q[t], np.zeros(n), np.zeros(n))[0])
            for p in range(len(self.pairs)):
                if (t, p) not in exact or w[t, p] <= WEIGHT_FLOOR:
                    continue
                res = exact[(t, p)]
                i, j = self.pairs[p]
                grad_d = res.normal @ (self._point_jacobian(j, res.getNearestPoint2()) - self._point_jacobian(i, res.getNearestPoint1()))
                J[p] += np.outer(-w[t, p] / LENGTH_SCALE * grad_d, self.basis.q[t])
        return g, J.reshape(len(self.pairs), n * m)

    def _point_jacobian(self, capsule: int, point: np.ndarray) -> np.ndarray:
        """(3, n) world-frame velocity Jacobian of ``point`` [m] fixed to the capsule's body."""
        joint = self.capsules[capsule].joint
        J = pin.getJointJacobian(self.robot.model, self.robot.data, joint, pin.LOCAL_WORLD_ALIGNED)[:, self.robot.v_idx]
        r = point - self.robot.data.oMi[joint].translation
        return J[:3] - pin.skew(r) @ J[3:]

    def track(self, alpha: np.ndarray, basis: FourierBasis) -> dict[str, np.ndarray]:
        """``min_capsule_distance``: (T,) smallest distance over the pairs at each instant [m]."""
        if not self.pairs:
            return {}
        rotations, centres = capsule_placements(self.robot, self.capsules, basis.q @ alpha.T)
        return {"min_capsule_distance": self._screen(rotations, centres).min(axis=1)}

    def check_samples(self, time: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> FineCheck:
        """Smallest distance over the postures q (T, n) and all pairs: the screen locates it, coal
        gives it (for every sample screened within ``CONFIRM`` of the smallest)."""
        if not self.pairs:
            return FineCheck(max_violation=-np.inf, details={}, where="no capsule pair")
        rotations, centres = capsule_placements(self.robot, self.capsules, q)
        screened = self._screen(rotations, centres)
        best, where = np.inf, (0, 0)
        for t, p in zip(*np.nonzero(screened <= screened.min() + CONFIRM)):
            d = self._distance(rotations, centres, t, p).min_distance
            if d < best:
                best, where = d, (t, p)
        i, j = self.pairs[where[1]]
        pair = f"{self.capsules[i].link}–{self.capsules[j].link}"
        return FineCheck(
            max_violation=(self.margin - best) / LENGTH_SCALE,
            details={"min_capsule_distance_m": float(best), "min_capsule_pair": pair,
                     "min_capsule_time_s": float(time[where[0]])},
            where=f"capsules {pair} {best * 100:.2f} cm apart (margin {self.margin * 100:.1f} cm)",
        )
