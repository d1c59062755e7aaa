"""The optional constraint sections of an ``optimize`` config: the centre-of-mass region (Eq. 52),
the zero-moment point (balance under acceleration), self-collision capsules (Eq. 53) and the world
around the robot."""

from __future__ import annotations

import math
from typing import Literal, Optional, Union

from pydantic import Field, PositiveFloat, model_validator

from excite_cli.config.base import Section


class ComConfig(Section):
    """Centre-of-mass region (Eq. 52): support links or centre [m], radius [m] or polygon [m]."""

    support_links: list[str] = Field(default_factory=list)
    """Support area: the convex hull of these links' lowest collision points (or give centre)."""
    centre: Optional[tuple[float, float]] = None
    """Explicit centre [m] of the region, [x, y] in the world frame."""
    radius: Optional[float] = Field(None, gt=0.0)
    """Disc radius [m] (the paper: 0.01); or give polygon."""
    polygon: Optional[list[tuple[float, float]]] = Field(None, min_length=3)
    """Convex region [m], vertices [[x, y], ...] relative to the centre."""

    @model_validator(mode="after")
    def _one_region(self) -> "ComConfig":
        if (self.radius is None) == (self.polygon is None):
            raise ValueError("give exactly one of radius [m] or polygon [[x, y], ...] [m]")
        if bool(self.support_links) == (self.centre is not None):
            raise ValueError("give exactly one of support_links or centre [x, y] [m]")
        return self


class ZmpConfig(Section):
    """Zero-moment point (ZMP) of a standing robot whose feet stay flat: inside the soles' support
    polygon shrunk by ``margin`` [m], with the ground pushing up (F_z > 0). Needs
    ``robot.floating_base: true``."""

    support_links: list[str] = Field(min_length=1)
    """The links whose lowest collision points touch the ground (the soles' contact points)."""
    margin: float = Field(0.02, ge=0.0)
    """Distance [m] the ZMP keeps from every edge of the support polygon."""
    friction: float = Field(0.5, gt=0.0, le=10.0)
    """Friction coefficient μ [1] of the soles: the held joints' feed-forward keeps forces in ‖f_xy‖ ≤ μ f_z."""


class CapsuleConfig(Section):
    """One capsule on a link: radius [m], segment end points in the link frame [m]."""

    link: str
    """The link it is fixed to."""
    radius: float = Field(gt=0.0)
    """Radius [m]."""
    start: tuple[float, float, float]
    """Segment start [m] in the link frame."""
    end: tuple[float, float, float]
    """Segment end [m] in the link frame."""


class SelfCollisionConfig(Section):
    """Self-collision (Eq. 53): capsules (``auto`` or given), ignored links, excluded pairs, margin [m]."""

    capsules: Union[Literal["auto"], list[CapsuleConfig]] = "auto"
    """`auto` (fitted to the URDF's collision geometry) or a list of capsules."""
    ignore_links: list[str] = Field(default_factory=list)
    """Links that get no capsule."""
    exclude_pairs: list[tuple[str, str]] = Field(default_factory=list)
    """Link pairs not checked (besides same-body and adjacent ones)."""
    margin: float = Field(0.01, ge=0.0)
    """Smallest allowed distance [m] between capsule surfaces."""


class WorldShapeConfig(Section):
    """A shape fixed in the world frame the robot's capsules keep ``margin`` [m] from: a half-space
    (``point`` on its plane, ``normal`` towards the robot's side: a floor, a table top), a sphere
    (``centre``, ``radius``), a capsule (``start``, ``end``, ``radius``) or a box (``centre``, side
    lengths ``size``, turned by ``rpy`` [rad] about x, y, z), all in metres."""

    name: str
    """A name for messages and plots."""
    type: Literal["half_space", "sphere", "capsule", "box"]
    """`half_space`, `sphere`, `capsule` or `box`."""
    point: Optional[tuple[float, float, float]] = None
    """A point [m] on a half-space's plane."""
    normal: Optional[tuple[float, float, float]] = None
    """A half-space's normal [m], towards the robot's side."""
    centre: Optional[tuple[float, float, float]] = None
    """Centre [m] of a sphere or a box."""
    start: Optional[tuple[float, float, float]] = None
    """Segment start [m] of a capsule."""
    end: Optional[tuple[float, float, float]] = None
    """Segment end [m] of a capsule."""
    radius: Optional[float] = Field(None, gt=0.0)
    """Radius [m] of a sphere or a capsule."""
    size: Optional[tuple[PositiveFloat, PositiveFloat, PositiveFloat]] = None
    """Side lengths [m] of a box."""
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Rotation [rad] of a box about x, y, z."""
    margin: float = Field(0.02, ge=0.0)
    """Smallest allowed distance [m] from the robot's capsules."""

    @model_validator(mode="after")
    def _fields_of_its_type(self) -> "WorldShapeConfig":
        needs = {
            "half_space": ("point", "normal"),
            "sphere": ("centre", "radius"),
            "capsule": ("start", "end", "radius"),
            "box": ("centre", "size"),
        }
        missing = [f for f in needs[self.type] if getattr(self, f) is None]
        if missing:
            raise ValueError(f"a {self.type} needs {', '.join(missing)}")
        if self.type == "half_space" and not 0.0 < math.hypot(*self.normal) < math.inf:
            raise ValueError("the normal of a half_space must not be zero")
        return self


class EnvironmentConfig(Section):
    """The world around the robot (issue 19): shapes its capsules (``auto``: fitted to the URDF's
    collision meshes, or given) keep away from, minus ``ignore_links``."""

    shapes: list[WorldShapeConfig] = Field(min_length=1)
    """Shapes fixed in the world frame."""
    capsules: Union[Literal["auto"], list[CapsuleConfig]] = "auto"
    """The robot's capsules: `auto` (fitted) or given, as for self_collision."""
    ignore_links: list[str] = Field(default_factory=list)
    """Links that get no capsule here."""


class ConstraintsConfig(Section):
    """Optional balance, self-collision and world constraints."""

    com: Optional[ComConfig] = None
    """The centre-of-mass region (Eq. 52), or none."""
    zmp: Optional[ZmpConfig] = None
    """The zero-moment point inside the support polygon, or none."""
    self_collision: Optional[SelfCollisionConfig] = None
    """Self-collision between capsules (Eq. 53), or none."""
    environment: Optional[EnvironmentConfig] = None
    """The world around the robot, or none."""
