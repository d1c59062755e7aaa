"""The support polygon of a standing robot: the convex hull of its soles' lowest collision points on
the ground plane, which the centre-of-mass region (Eq. 52) is centred in and the zero-moment point
keeps inside (Kajita et al., *Introduction to Humanoid Robotics*, 2014, ch. 3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from excite_cli.collision.geometry import world_points
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError


@dataclass(frozen=True)
class SupportPolygon:
    """A convex polygon on the ground plane z = ``height``.

    Attributes:
        vertices: (K, 2) corners [m], world x, y, counter-clockwise.
        height: z [m] of the ground plane (the soles' lowest point).
        normals: (K, 2) outward unit normal of edge k (from vertex k to k + 1).
        offsets: (K,) n_kᵀv for any point v of edge k [m]: a point p is inside when n_kᵀp ≤ offsets_k.
    """

    vertices: np.ndarray
    height: float
    normals: np.ndarray
    offsets: np.ndarray

    @classmethod
    def from_points(cls, points: np.ndarray, height: float) -> "SupportPolygon":
        """The convex hull of ``points`` (m, 2) [m] on the plane z = ``height`` [m].

        Raises:
            QhullError: the points span no area.
        """
        v = points[ConvexHull(points).vertices]  # counter-clockwise in 2-D
        edge = np.roll(v, -1, axis=0) - v
        normals = np.stack([edge[:, 1], -edge[:, 0]], axis=1) / np.linalg.norm(edge, axis=1)[:, None]
        for array in (v, normals):
            array.flags.writeable = False
        offsets = np.einsum("kx,kx->k", normals, v)
        offsets.flags.writeable = False
        return cls(v, float(height), normals, offsets)

    @property
    def centroid(self) -> np.ndarray:
        """(2,) area centroid [m]."""
        v = self.vertices
        cross = v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]
        area = cross.sum() / 2.0
        return np.array(
            [((v[:, 0] + np.roll(v[:, 0], -1)) * cross).sum(), ((v[:, 1] + np.roll(v[:, 1], -1)) * cross).sum()]
        ) / (6.0 * area)

    def shrunk(self, margin: float) -> np.ndarray:
        """(K, 2) corners [m] of the polygon whose edges lie ``margin`` [m] inside these (each corner where
        two neighbouring shifted edges meet; a margin wider than the polygon's inradius crosses them)."""
        normals, offsets = self.normals, self.offsets - margin
        before = np.roll(np.arange(len(offsets)), 1)
        pairs = np.stack([normals[before], normals], axis=1)  # (K, 2, 2): edges k − 1 and k meet at corner k
        return np.linalg.solve(pairs, np.stack([offsets[before], offsets], axis=1)[..., None])[..., 0]

    def margins(self, points: np.ndarray) -> np.ndarray:
        """(T,) signed distance [m] of each of ``points`` (T, 2) inside the polygon: the least
        offsets_k − n_kᵀp over the edges (the distance to the nearest edge inside, ≤ 0 outside)."""
        return (self.offsets - points @ self.normals.T).min(axis=1)


def sole_points(robot: Robot, links: list[str], height: float, field: str) -> list[np.ndarray]:
    """Each of ``links``' collision-geometry points (k_i, 3) [m, world frame] within ``height`` [m] of
    the lowest point of them all, at the home posture (the robot standing on them): its sole's contact
    points, possibly none.

    Raises:
        ExciteError: (``field``) a link without collision geometry, or one an active joint moves (a
            hand: soles stand still).
    """
    active = {robot.model.getJointId(name): name for name in robot.joint_names}
    for link in links:
        frame = robot.model.getFrameId(link)
        chain = robot.model.supports[robot.model.frames[frame].parentJoint] if frame < robot.model.nframes else []
        moving = [active[j] for j in chain if j in active]
        if moving:
            raise ExciteError(field, f"'{link}' is moved by the active joint '{moving[0]}'; a sole stands still", link)
    points = [world_points(robot, link, robot.home, field) for link in links]
    lowest = min(p[:, 2].min() for p in points)
    return [p[p[:, 2] <= lowest + height] for p in points]


#: [m] a sole whose contact points lie in a strip narrower than this stands on an edge (a flat foot
#: touches the ground over several centimetres each way; the G1's heels alone over 3.5 mm).
EDGE = 0.01


def soles_on_an_edge(robot: Robot, links: list[str], height: float, field: str) -> list[tuple[str, int]]:
    """(link, contact points) of the soles of ``links`` (:func:`sole_points`) that touch the ground on
    two or more points in a strip narrower than :data:`EDGE` at the home posture: standing on an edge
    (held joints that tilt the foot: a bent knee without the ankle that levels it). A point foot (one
    point) is not one."""
    out = []
    for link, points in zip(links, sole_points(robot, links, height, field)):
        xy = points[:, :2] - points[:, :2].mean(axis=0)
        across = xy @ np.linalg.svd(xy, full_matrices=False)[2][-1]  # along the narrowest direction
        if len(points) >= 2 and np.ptp(across) < EDGE:
            out.append((link, len(points)))
    return out


def tilted_stance(edges: list[tuple[str, int]], what: str) -> ExciteError:
    """The error of a support polygon that fails because soles stand on an edge (``edges``: see
    :func:`soles_on_an_edge`): the held joints are at fault, not ``what`` (the field that failed)."""
    named = ", ".join(f"'{link}' ({count} points in a strip under {100 * EDGE:g} cm)" for link, count in edges)
    return ExciteError(
        "robot.locked_joints",
        f"at the home posture the soles of {named} touch the ground along an edge, so {what}: the held joints "
        "tilt the feet; they must keep the soles flat (a bent knee needs the hip and ankle pitch that level the "
        "foot, as excite init drafts a stance)",
    )


def support_polygon(robot: Robot, links: list[str], height: float, field: str) -> SupportPolygon:
    """The hull of the soles' contact points of ``links`` (:func:`sole_points`) on the ground plane.

    Raises:
        ExciteError: (``field``) a link without collision geometry, or soles spanning no area
            (``robot.locked_joints`` where soles stand on an edge: :func:`tilted_stance`).
    """
    sole = np.vstack(sole_points(robot, links, height, field))
    try:
        return SupportPolygon.from_points(sole[:, :2], sole[:, 2].min())
    except (QhullError, ValueError):  # degenerate input (too few, collinear or coincident points)
        edges = soles_on_an_edge(robot, links, height, field)
        if edges:
            raise tilted_stance(edges, f"{field} span no area") from None
        raise ExciteError(field, "the soles of these links span no area") from None
