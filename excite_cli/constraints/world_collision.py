"""The world around the robot (issue 19): every robot capsule keeps a margin from shapes fixed in
the world frame: half-spaces (a floor, a table top), spheres, capsules and boxes.

Distances are closed forms over all (instant, capsule, shape) at once: to a half-space with unit
normal n through point o, a segment's closest point is the end point of least height h = n·(x − o),
d = h − r; to a sphere or a world capsule, the closest points of the two segments
(:func:`~excite_cli.collision.segments.segment_closest_points`, a sphere being a segment of length 0),
d = |c₂ − c₁| − r₁ − r₂; to a box, coal's distance, nearest points and normal (negative inside).
d varies as ∂d = nᵀ J_x ∂q along the normal n from the world shape to the robot's point x
(:meth:`BatchKinematics.distance_rates`); per (capsule, shape), s_t = (margin − d_t)/L is aggregated
over the grid like the self-collision pairs. Capsules on links no active joint moves are left out:
their distances cannot change (the base bolted on the table).
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from excite_cli.collision.capsules import Capsule, capsule_frames, segment_ends
from excite_cli.collision.segments import segment_closest_points
from excite_cli.collision.world import ShapeKind, WorldShape
from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.constraints.lse import ACCEPT_MARGIN, smooth_max, smooth_max_value
from excite_cli.constraints.self_collision import LENGTH_SCALE
from excite_cli.dynamics.kinematics import BatchKinematics
from excite_cli.dynamics.robot import Robot
from excite_cli.memo import once
from excite_cli.trajectory.fourier import FourierBasis


def distance_bound(robot: Robot, capsule: Capsule, shape: WorldShape) -> float:
    """A lower bound [m] on the distance between ``capsule`` and ``shape`` at every posture.

    Every point of the capsule's segment stays within the reach R of the origin p₀ of the first
    active joint that moves it (p₀ is fixed: no active joint is above it): R = the lengths of the
    joint offsets below it plus the farther segment end (rotations keep lengths). So d ≥ D(p₀) − R −
    radius, D the distance from p₀ to the half-space's plane, the sphere or capsule's segment minus
    its radius, or the box's centre minus its half-diagonal. −inf when a joint below p₀ is not
    revolute (its offset is not bounded by a length).
    """
    model = robot.model
    active = {int(model.getJointId(n)) for n in robot.joint_names}
    chain = [j for j in model.supports[capsule.joint] if j > 0]
    below = chain[next(k for k, j in enumerate(chain) if j in active) :]
    if any(not model.joints[j].shortname().startswith("JointModelR") for j in below):
        return -np.inf
    data = model.createData()
    pin.forwardKinematics(model, data, robot.q_reference)
    origin = data.oMi[below[0]].translation
    reach = sum(float(np.linalg.norm(model.jointPlacements[j].translation)) for j in below[1:])
    reach += max(float(np.linalg.norm(capsule.start)), float(np.linalg.norm(capsule.end))) + capsule.radius
    if shape.kind is ShapeKind.HALF_SPACE:
        away = float(shape.end @ (origin - shape.start))
    elif shape.kind is ShapeKind.BOX:
        away = float(np.linalg.norm(origin - shape.start) - np.linalg.norm(shape.size) / 2.0)
    else:
        closest = segment_closest_points(shape.start, shape.end, origin, origin)[0]
        away = float(np.linalg.norm(origin - closest)) - shape.radius
    return away - reach


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


class WorldCollision(Constraint):
    """One aggregated inequality per (moving robot capsule, world shape) that can come within the
    shape's margin (:func:`distance_bound`).

    Args:
        robot: the robot.
        basis: Fourier basis on the constraint grid.
        capsules: the robot's capsules (those no active joint moves are left out).
        shapes: the world shapes.
    """

    name = "world_collision"
    field = "constraints.environment"
    grid_margin = ACCEPT_MARGIN
    track_units = {"min_world_distance": "m"}

    def __init__(self, robot: Robot, basis: FourierBasis, capsules: list[Capsule], shapes: list[WorldShape]):
        self.kinematics = BatchKinematics(robot)
        ancestors = self.kinematics.ancestors
        self.basis, self.shapes = basis, shapes
        self.capsules = [c for c in capsules if ancestors[c.joint].any()]
        bounds = [[distance_bound(robot, c, s) for s in shapes] for c in self.capsules]
        self.pairs = [
            (c, s) for c in range(len(self.capsules)) for s in range(len(shapes)) if bounds[c][s] <= shapes[s].margin
        ]
        self._capsule = np.array([c for c, _ in self.pairs], dtype=int)
        self._shape = np.array([s for _, s in self.pairs], dtype=int)
        self._radii = np.array([self.capsules[c].radius for c in self._capsule])
        self._margin = np.array([shapes[s].margin for s in self._shape])
        self._solids = [coal.Capsule(c.radius, float(np.linalg.norm(c.end - c.start))) for c in self.capsules]
        self._moves = (
            ancestors[[self.capsules[c].joint for c in self._capsule]].astype(float).reshape(-1, robot.n_joints)
        )

    def in_words(self) -> str:
        """The rows, in words (for ``check``)."""
        return f"one per capsule and world shape ({len(self.pairs)})"

    def shapes_in_reach(self) -> list[str]:
        """The shapes of :attr:`pairs` (:meth:`Constraint.shapes_in_reach`)."""
        return sorted({self.shapes[s].name for _, s in self.pairs})

    def always_within(self, Q: np.ndarray) -> list[tuple[str, float]]:
        """Links within a shape's margin at every posture Q (K, n), with that margin [m]."""
        if not self.pairs:
            return []
        d = self.distances(Q)
        return [
            (self.capsules[i].link, self.shapes[s].margin)
            for k, (i, s) in enumerate(self.pairs)
            if np.all(d[:, k] < self.shapes[s].margin)
        ]

    def clearance(self, Q: np.ndarray) -> np.ndarray:
        """(K,) the smallest distance [m] beyond its shape's margin over every pair at the postures Q (K, n)."""
        return (self.distances(Q) - self._margin).min(axis=1, initial=np.inf)

    def distances(self, Q: np.ndarray) -> np.ndarray:
        """Distances (T, P) [m] of every (capsule, shape) pair at the configurations Q (T, n)."""
        return self._closest_points(Q)[0]

    def _closest(self, Q: np.ndarray) -> tuple[np.ndarray, ...]:
        """At the configurations Q (T, n): distances d (T, P) [m], the robot's closest points (3, T, P),
        the unit normals (3, T, P) from the world shape to them, and the joint placements."""
        return once(self, "closest", Q, lambda: self._closest_points(Q))

    def _closest_points(self, Q: np.ndarray) -> tuple[np.ndarray, ...]:
        """:meth:`_closest`, computed."""
        start, end, R, p = segment_ends(self.kinematics, self.capsules, Q)
        a, b = start[..., self._capsule], end[..., self._capsule]
        d, point, normal = np.empty(a.shape[1:]), np.empty_like(a), np.empty_like(a)
        frames = None  # capsule placements, for the boxes
        for k, shape in enumerate(self.shapes):
            cols = self._shape == k
            ak, bk = a[..., cols], b[..., cols]
            if shape.kind is ShapeKind.BOX:
                frames = frames or capsule_frames(R, p, self.capsules)
                d[:, cols], point[..., cols], normal[..., cols] = self._to_box(shape, *frames, np.flatnonzero(cols))
            elif shape.kind is ShapeKind.HALF_SPACE:
                n, o = shape.end[:, None, None], shape.start[:, None, None]
                ha, hb = (((x - o) * n).sum(axis=0) for x in (ak, bk))
                point[..., cols] = np.where(ha <= hb, ak, bk)
                d[:, cols] = np.minimum(ha, hb) - self._radii[cols]
                normal[..., cols] = np.broadcast_to(n, ak.shape)
            else:
                c1, c2 = segment_closest_points(shape.start[:, None, None], shape.end[:, None, None], ak, bk)
                gap = c2 - c1
                length = np.sqrt((gap**2).sum(axis=0))
                point[..., cols], normal[..., cols] = c2, gap / np.maximum(length, 1e-12)
                d[:, cols] = length - shape.radius - self._radii[cols]
        return d, point, normal, R, p

    def _to_box(
        self, box: WorldShape, rotations: np.ndarray, centres: np.ndarray, pairs: np.ndarray
    ) -> tuple[np.ndarray, ...]:
        """coal's distances (T, K) [m] of the pairs ``pairs`` (K,) to ``box``, the nearest points on
        the robot (3, T, K) and the unit normals from the box to them, from the capsules' placements
        (rotations (T, C, 3, 3), centres (T, C, 3), :func:`capsule_frames`)."""
        solid, placement = coal.Box(*box.size), coal.Transform3s(box.rotation, box.start)
        T, K = rotations.shape[0], pairs.size
        d, point, normal = np.empty((T, K)), np.empty((3, T, K)), np.empty((3, T, K))
        for k, c in enumerate(self._capsule[pairs]):
            for t in range(T):
                result = coal.DistanceResult()
                placed = coal.Transform3s(rotations[t, c], centres[t, c])
                coal.distance(self._solids[c], placed, solid, placement, coal.DistanceRequest(), result)
                d[t, k], point[:, t, k], normal[:, t, k] = (
                    result.min_distance,
                    result.getNearestPoint1(),
                    -result.normal,
                )
        return d, point, normal

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One aggregated value per (capsule, shape) (P,) and the Jacobian (P, α.size)."""
        n, m = alpha.shape
        P = len(self.pairs)
        if not P:
            return np.zeros(0), np.zeros((0, n * m))
        closest = self._closest(self.basis.q @ alpha.T)
        return aggregated_distances(self.kinematics, self.basis, self._margin, *closest, self._moves)

    def values(self, alpha: np.ndarray) -> np.ndarray:
        """The aggregated values of :meth:`evaluate` (P,) without the Jacobian."""
        if not self.pairs:
            return np.zeros(0)
        return smooth_max_value((self._margin - self._closest(self.basis.q @ alpha.T)[0]) / LENGTH_SCALE, axis=0)

    def track(self, alpha: np.ndarray, basis: FourierBasis) -> dict[str, np.ndarray]:
        """``min_world_distance``: (T,) the smallest distance over (capsule, shape) at each instant [m]."""
        if not self.pairs:
            return {}
        return {"min_world_distance": self._closest(basis.q @ alpha.T)[0].min(axis=1)}

    def check_samples(self, time: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> FineCheck:
        """The (capsule, shape) that comes closest to its margin over the postures q (T, n) [rad]."""
        if not self.pairs:
            return FineCheck(max_violation=-np.inf, details={}, where="no moving capsule")
        d = self._closest(q)[0]
        slack = (self._margin - d) / LENGTH_SCALE
        t, k = np.unravel_index(np.argmax(slack), slack.shape)
        link, shape = self.capsules[self._capsule[k]].link, self.shapes[self._shape[k]]
        return FineCheck(
            max_violation=float(slack[t, k]),
            details={
                "min_world_distance_m": float(d.min()),
                "closest_world_pair": f"{link}–{shape.name}",
                "closest_world_time_s": float(time[t]),
            },
            where=f"link {link} {d[t, k] * 100:.2f} cm from {shape.name} (margin {shape.margin * 100:.1f} cm)",
        )
