"""Capsules: closest points of segments against closed forms, a fitted capsule covering its points,
and the collision-geometry points they are fitted to against pinocchio's placements."""

import numpy as np
import pinocchio as pin
import pytest
from conftest import CONFIGS, robot_of

from excite_cli.collision.capsules import fit_capsule, segment_closest_points
from excite_cli.collision.geometry import link_points, links_with_geometry, world_points
from excite_cli.config_file import load_problem


def segment_distances(p1, q1, p2, q2):
    c1, c2 = segment_closest_points(p1, q1, p2, q2)
    return np.linalg.norm(c2 - c1, axis=0)


def test_segment_distance_closed_forms():
    z = np.zeros(3)
    assert segment_distances(z, np.array([1.0, 0, 0]), np.array([0.5, 1, 0]), np.array([0.5, 2, 0])) == pytest.approx(
        1.0
    )
    assert segment_distances(z, np.array([1.0, 0, 0]), np.array([2.0, 0, 0]), np.array([3.0, 0, 0])) == pytest.approx(
        1.0
    )
    assert segment_distances(z, z, np.array([0, 3.0, 4.0]), np.array([0, 3.0, 4.0])) == pytest.approx(5.0)
    point = np.array([0.5, 2.0, 0.0])
    assert segment_distances(z, np.array([1.0, 0, 0]), point, point) == pytest.approx(2.0)
    assert segment_distances(point, point, z, np.array([1.0, 0, 0])) == pytest.approx(2.0)
    skew = segment_distances(
        np.array([-1.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0, -1.0, 2]), np.array([0, 1.0, 2])
    )
    assert skew == pytest.approx(2.0)


def test_fitted_capsule_covers_its_points():
    rng = np.random.default_rng(0)
    points = rng.normal(size=(500, 3)) * [0.2, 0.03, 0.02] + [0.1, -0.2, 0.3]
    radius, start, end = fit_capsule(points)
    assert (
        segment_distances(
            np.broadcast_to(start[:, None], points.T.shape),
            np.broadcast_to(end[:, None], points.T.shape),
            points.T,
            points.T,
        ).max()
        <= radius + 1e-12
    )
    assert np.linalg.norm(end - start) > 0.5  # along the long axis


def test_collision_points_follow_their_link_in_the_world():
    robot = robot_of(load_problem(CONFIGS / "panda.yaml"), collision=True)
    assert "panda_link7" in links_with_geometry(robot) and "panda_hand" in links_with_geometry(robot)
    q = robot.home + 0.1
    local, joint = link_points(robot, "panda_link7")
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, robot.state(q, 0 * q, 0 * q)[0])
    expected = np.array([data.oMi[joint].act(p) for p in local])
    np.testing.assert_allclose(world_points(robot, "panda_link7", q), expected, atol=1e-12)
    with pytest.raises(Exception, match="no collision geometry"):
        link_points(robot, "not_a_link")
