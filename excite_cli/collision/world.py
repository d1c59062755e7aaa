"""Shapes fixed in the world (``constraints.environment``) that the robot's capsules keep a margin
from: half-spaces, spheres, capsules and boxes, as the config gives them."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np
import pinocchio as pin

from excite_cli.config import EnvironmentConfig


class ShapeKind(StrEnum):
    """The kinds of shape fixed in the world (``constraints.environment.shapes[].type``)."""

    HALF_SPACE = "half_space"
    SPHERE = "sphere"
    CAPSULE = "capsule"
    BOX = "box"


@dataclass(frozen=True)
class WorldShape:
    """A shape fixed in the world frame.

    Attributes:
        name: its name in the config, for messages.
        kind: a half-space, a sphere, a capsule or a box.
        start: (3,) a point on the plane, the sphere's centre or the capsule's first end [m].
        end: (3,) the plane's unit normal (towards the robot's side) or the capsule's second end
            [m] (the centre again for a sphere).
        radius: [m], 0 for a half-space or a box.
        margin: distance every robot capsule keeps [m].
        size: (3,) a box's side lengths [m] (its centre is ``start`` and ``end``).
        rotation: (3, 3) a box's orientation in the world frame.
    """

    name: str
    kind: ShapeKind
    start: np.ndarray
    end: np.ndarray
    radius: float
    margin: float
    size: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))


def world_shapes(cfg: EnvironmentConfig | None) -> list[WorldShape]:
    """The shapes of ``constraints.environment`` (their fields checked by the config); none without one."""
    shapes = []
    for s in cfg.shapes if cfg else []:
        kind = ShapeKind(s.type)
        if kind is ShapeKind.HALF_SPACE:
            normal = np.asarray(s.normal, dtype=float)
            shapes.append(
                WorldShape(s.name, kind, np.asarray(s.point, float), normal / np.linalg.norm(normal), 0.0, s.margin)
            )
        elif kind in (ShapeKind.SPHERE, ShapeKind.BOX):
            centre, rotation = np.asarray(s.centre, dtype=float), pin.rpy.rpyToMatrix(*s.rpy)
            size = np.asarray(s.size if s.size else (0.0, 0.0, 0.0), dtype=float)
            shapes.append(WorldShape(s.name, kind, centre, centre, s.radius or 0.0, s.margin, size, rotation))
        else:
            shapes.append(
                WorldShape(s.name, kind, np.asarray(s.start, float), np.asarray(s.end, float), s.radius, s.margin)
            )
    return shapes
