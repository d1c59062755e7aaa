"""Capsules on links (Eq. 53), given in the config or fitted to each link's URDF collision geometry,
and the pairs that need checking."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from excite_cli.collision.geometry import link_points, links_with_geometry
from excite_cli.config import EnvironmentConfig, SelfCollisionConfig
from excite_cli.dynamics.kinematics import BatchKinematics
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError


@dataclass(frozen=True)
class Capsule:
    """A segment [start, end] swept by a sphere of ``radius`` [m], fixed to a link.

    Attributes:
        link: link name.
        joint: index of the link's parent joint in the reduced model.
        radius: [m].
        start, end: (3,) segment end points in the parent joint's frame [m].
    """

    link: str
    joint: int
    radius: float
    start: np.ndarray
    end: np.ndarray


def fit_capsule(points: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Smallest capsule around ``points`` (k, 3) along their principal axis: radius [m], start, end.

    The radius is the largest distance of a point from the axis; the end points are then pulled in
    as far as the hemispherical caps still cover every point.
    """
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre, full_matrices=False)
    axis = vt[0]
    along = (points - centre) @ axis
    across = np.linalg.norm(points - centre - np.outer(along, axis), axis=1)
    radius = float(across.max())
    cap = np.sqrt(np.maximum(radius**2 - across**2, 0.0))
    top, bottom = float((along - cap).max()), float((along + cap).min())
    if bottom > top:  # a sphere is enough
        top = bottom = (top + bottom) / 2.0
    return max(radius, 1e-4), centre + bottom * axis, centre + top * axis


def capsules_from_config(
    cfg: SelfCollisionConfig | EnvironmentConfig, robot: Robot, field: str = "constraints.self_collision"
) -> list[Capsule]:
    """Capsules of ``constraints.self_collision`` (or ``constraints.environment``, ``field``): the
    given ones, or one fitted per link with collision geometry (``auto``), minus ``ignore_links``.

    Raises:
        ExciteError: an unknown link name.
    """
    frames = {f.name: f for f in robot.model.frames}
    for name in cfg.ignore_links:
        if name not in frames:
            raise ExciteError(f"{field}.ignore_links", f"'{name}' is not a link of the robot")
    capsules = []
    if cfg.capsules == "auto":
        for link in links_with_geometry(robot):
            if link not in cfg.ignore_links:
                points, joint = link_points(robot, link)
                radius, start, end = fit_capsule(points)
                capsules.append(Capsule(link, joint, radius, start, end))
        return capsules
    for spec in cfg.capsules:
        if spec.link not in frames:
            raise ExciteError(f"{field}.capsules", f"'{spec.link}' is not a link of the robot")
        if spec.link in cfg.ignore_links:
            continue
        frame = frames[spec.link]
        to_joint = frame.placement
        capsules.append(
            Capsule(
                spec.link,
                int(frame.parentJoint),
                spec.radius,
                to_joint.act(np.asarray(spec.start, dtype=float)),
                to_joint.act(np.asarray(spec.end, dtype=float)),
            )
        )
    return capsules


def _moves(robot: Robot, joint: int) -> bool:
    """Whether an active joint is on the path from the root to ``joint``."""
    active = {int(robot.model.getJointId(n)) for n in robot.joint_names}
    while joint > 0:
        if joint in active:
            return True
        joint = robot.model.parents[joint]
    return False


def capsule_pairs(cfg: SelfCollisionConfig, robot: Robot, capsules: list[Capsule]) -> list[tuple[int, int]]:
    """Index pairs (i, j) to keep apart: capsules on different bodies that are not adjacent (one
    body's joint the parent of the other's) and can move relative to each other, minus
    ``exclude_pairs``.

    Raises:
        ExciteError: an excluded pair names a link without a capsule.
    """
    names = [c.link for c in capsules]
    excluded = set()
    for a, b in cfg.exclude_pairs:
        for link in (a, b):
            if link not in names:
                raise ExciteError("constraints.self_collision.exclude_pairs", f"'{link}' has no capsule")
        excluded.add(frozenset((a, b)))
    parents = robot.model.parents
    pairs = []
    for i, ci in enumerate(capsules):
        for j in range(i + 1, len(capsules)):
            cj = capsules[j]
            if ci.joint == cj.joint or parents[ci.joint] == cj.joint or parents[cj.joint] == ci.joint:
                continue
            if not (_moves(robot, ci.joint) or _moves(robot, cj.joint)):
                continue
            if frozenset((ci.link, cj.link)) in excluded:
                continue
            pairs.append((i, j))
    return pairs


def capsule_frame(capsule: Capsule) -> pin.SE3:
    """Placement in the parent joint's frame of a frame centred on the capsule with z along its axis."""
    axis = capsule.end - capsule.start
    length = np.linalg.norm(axis)
    z = axis / length if length > 1e-12 else np.array([0.0, 0.0, 1.0])
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return pin.SE3(np.column_stack([x, np.cross(z, x), z]), (capsule.start + capsule.end) / 2.0)


def capsule_frames(R: np.ndarray, p: np.ndarray, capsules: list[Capsule]) -> tuple[np.ndarray, np.ndarray]:
    """World placements of every capsule's centred frame (z along the axis) from joint placements
    (rotations (T, J, 3, 3), origins (T, J, 3), :meth:`BatchKinematics.placements`): rotations
    (T, C, 3, 3) and centres (T, C, 3) [m]."""
    joints = [c.joint for c in capsules]
    local = [capsule_frame(c) for c in capsules]
    local_R = np.stack([m.rotation for m in local])
    local_p = np.stack([m.translation for m in local])
    rotations = np.einsum("tcij,cjk->tcik", R[:, joints], local_R)
    centres = np.einsum("tcij,cj->tci", R[:, joints], local_p) + p[:, joints]
    return rotations, centres


def segment_ends(
    kinematics: BatchKinematics, capsules: list[Capsule], Q: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every capsule's segment in the world frame at each configuration of the active joints Q (T, n):
    start and end points (3, T, C) [m] (coordinates first, as
    :func:`~excite_cli.collision.segments.segment_closest_points` takes them), with
    the joint placements they came from (:meth:`BatchKinematics.placements`: rotations (T, J, 3, 3),
    origins (T, J, 3))."""
    R, p = kinematics.placements(Q)
    joints = [c.joint for c in capsules]
    starts, ends = np.stack([c.start for c in capsules]), np.stack([c.end for c in capsules])
    Rc, pc = R[:, joints], p[:, joints]
    return (
        np.einsum("tcij,cj->itc", Rc, starts) + pc.transpose(2, 0, 1),
        np.einsum("tcij,cj->itc", Rc, ends) + pc.transpose(2, 0, 1),
        R,
        p,
    )
