"""A sole's contact points in its link's frame, for MuJoCo's spheres: placed back by forward kinematics
at the standing posture they lie on the ground plane and span the support polygon the ZMP is kept in."""

import numpy as np
import pinocchio as pin
from conftest import CONFIGS
from scipy.spatial import ConvexHull

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.rehearsal.soles import mesh_soles


def test_the_soles_points_placed_back_span_the_zmp_polygon_on_the_ground():
    problem = load_problem(CONFIGS / "g1_arms.yaml")
    excitation = build_excitation(problem)
    robot, links = excitation.robot, problem.constraints.zmp.support_links
    polygon = next(
        c for c in excitation.constraints if c.ground_point(robot.home[None], *[0 * robot.home[None]] * 2) is not None
    ).polygon
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.state(robot.home, 0 * robot.home, 0 * robot.home)[0])
    world = []
    for link, (points, up) in mesh_soles(robot, links).items():
        placement = data.oMf[robot.model.getFrameId(link)]
        world.append(points @ placement.rotation.T + placement.translation)
        np.testing.assert_allclose(placement.rotation @ up, [0, 0, 1], atol=1e-9)
    world = np.vstack(world)
    np.testing.assert_allclose(world[:, 2], polygon.height, atol=1e-3)  # CONTACT_HEIGHT: points within 1 mm
    hull = world[ConvexHull(world[:, :2]).vertices, :2]
    assert sorted(map(tuple, np.round(hull, 4))) == sorted(map(tuple, np.round(polygon.vertices, 4)))
