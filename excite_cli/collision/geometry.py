"""Points of a link's collision geometry (URDF), for fitting capsules and finding the support area."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError


def shape_points(shape: coal.CollisionGeometry) -> np.ndarray:
    """(k, 3) points on the surface of one collision shape, in its own frame [m]."""
    if hasattr(shape, "vertices") and hasattr(shape, "num_vertices"):
        return np.asarray(shape.vertices(), dtype=float)
    directions = np.vstack(
        [np.eye(3), -np.eye(3), np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T / np.sqrt(3)]
    )
    if isinstance(shape, coal.Sphere):
        return shape.radius * directions
    if isinstance(shape, coal.Box):
        return np.array(np.meshgrid(*[[-h, h] for h in shape.halfSide])).reshape(3, -1).T
    if isinstance(shape, (coal.Cylinder, coal.Capsule)):
        angle = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        ring = np.stack([shape.radius * np.cos(angle), shape.radius * np.sin(angle), np.zeros_like(angle)], axis=1)
        ends = [ring + [0, 0, z] for z in (-shape.halfLength, shape.halfLength)]
        if isinstance(shape, coal.Capsule):
            ends += [np.array([[0, 0, -shape.halfLength - shape.radius], [0, 0, shape.halfLength + shape.radius]])]
        return np.vstack(ends)
    raise ExciteError(
        "constraints.self_collision.capsules",
        f"collision shape {type(shape).__name__} is not supported",
        type(shape).__name__,
        "capsules given in the config",
    )


def links_with_geometry(robot: Robot) -> list[str]:
    """Names of the links that carry collision geometry, in URDF order."""
    names: list[str] = []
    for obj in robot.collision_model.geometryObjects:
        name = robot.model.frames[obj.parentFrame].name
        if name not in names:
            names.append(name)
    return names


def link_points(robot: Robot, link: str, field: str = "constraints.self_collision") -> tuple[np.ndarray, int]:
    """Points of every collision shape of ``link`` in its parent joint's frame [m], (k, 3), and that
    joint's index in the reduced model.

    Raises:
        ExciteError: the link has no collision geometry (the message names ``field``).
    """
    parts, joint = [], None
    for obj in robot.collision_model.geometryObjects:
        if robot.model.frames[obj.parentFrame].name == link:
            local = shape_points(obj.geometry)  # a mesh is loaded at its URDF scale already
            parts.append(local @ obj.placement.rotation.T + obj.placement.translation)
            joint = obj.parentJoint
    if joint is None:
        raise ExciteError(field, f"link '{link}' has no collision geometry in the URDF (or is not a link)")
    return np.vstack(parts), int(joint)


def world_points(robot: Robot, link: str, q: np.ndarray, field: str = "constraints.com.support_links") -> np.ndarray:
    """(k, 3) collision-geometry points of ``link`` in the world frame at active joints ``q`` [m].

    Raises:
        ExciteError: the link has no collision geometry (the message names ``field``).
    """
    points, joint = link_points(robot, link, field)
    qf = robot.state(q, np.zeros_like(q), np.zeros_like(q))[0]
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, qf)
    placement = data.oMi[joint]
    return points @ placement.rotation.T + placement.translation
