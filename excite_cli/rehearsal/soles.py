"""A standing robot's soles as MuJoCo gets them: excite's contact points in each sole's frame."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.spatial import ConvexHull

from excite_cli.constraints.support import sole_points
from excite_cli.constraints.zmp import CONTACT_HEIGHT
from excite_cli.dynamics.robot import Robot


def mesh_soles(robot: Robot, links: list[str]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """{link: (the corners of its contact points' hull (k, 3) [m], the world's up (3,))} in each support
    link's frame at the home posture: excite's soles (:func:`~excite_cli.constraints.support.sole_points`),
    for MuJoCo's spheres where a sole is a mesh.

    Raises:
        ExciteError: (``constraints.zmp.support_links``) a link with no collision geometry.
    """
    found = {}
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.state(robot.home, 0 * robot.home, 0 * robot.home)[0])
    for link, points in zip(links, sole_points(robot, links, CONTACT_HEIGHT, "constraints.zmp.support_links")):
        placement = data.oMf[robot.model.getFrameId(link)]
        corners = points[ConvexHull(points[:, :2]).vertices] if len(points) > 2 else points
        found[link] = ((corners - placement.translation) @ placement.rotation, placement.rotation[2].copy())
    return found
