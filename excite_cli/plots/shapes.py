"""Shapes drawn in a 2-D view of the robot (the posture strip): a capsule's outline, the world
shapes of ``constraints.environment``."""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull

from excite_cli.collision.world import ShapeKind, WorldShape


def stadium(a: np.ndarray, b: np.ndarray, radius: float, points: int = 12) -> np.ndarray:
    """(2·points + 2, 2) outline of the 2-D capsule around the segment [a, b] (its projection)."""
    d = b - a
    angle = np.arctan2(d[1], d[0]) if np.linalg.norm(d) > 1e-12 else 0.0
    arc = np.linspace(-np.pi / 2, np.pi / 2, points)
    ends = [
        b + radius * np.column_stack([np.cos(angle + arc), np.sin(angle + arc)]),
        a + radius * np.column_stack([np.cos(angle + np.pi + arc), np.sin(angle + np.pi + arc)]),
    ]
    return np.vstack(ends)


#: The eight corners of a box as signs of its half sides.
CORNERS = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]


def draw_shape(ax, shape: WorldShape, axis: int, sign: float) -> None:
    """A world shape in a view whose horizontal is world axis ``axis`` times ``sign`` and vertical z."""

    def h(x: np.ndarray) -> np.ndarray:
        return np.array([sign * x[axis], x[2]])

    if shape.kind is ShapeKind.BOX:
        corners = np.array([h(shape.start + shape.rotation @ (shape.size * np.array(c) / 2)) for c in CORNERS])
        outline = corners[ConvexHull(corners).vertices]
        ax.fill(outline[:, 0], outline[:, 1], color="0.5", alpha=0.4, linewidth=0)
        return
    if shape.kind is not ShapeKind.HALF_SPACE:
        outline = stadium(h(shape.start), h(shape.end), shape.radius)
        ax.fill(outline[:, 0], outline[:, 1], color="0.5", alpha=0.4, linewidth=0)
        return
    normal, point = h(shape.end), h(shape.start)
    if np.linalg.norm(normal) < 1e-9:  # the plane is the view's own: nothing to draw
        return
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    direction = np.array([-normal[1], normal[0]]) / np.linalg.norm(normal)
    span = 2 * max(x1 - x0, y1 - y0)
    a, b = point - span * direction, point + span * direction
    behind = -normal / np.linalg.norm(normal) * span
    ax.fill(
        [a[0], b[0], b[0] + behind[0], a[0] + behind[0]],
        [a[1], b[1], b[1] + behind[1], a[1] + behind[1]],
        color="0.5",
        alpha=0.3,
        linewidth=0,
    )
    ax.plot([a[0], b[0]], [a[1], b[1]], color="0.4", linewidth=0.8)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
