"""Capsules: closest points of segments against closed forms, a fitted capsule covering its points,
and the collision-geometry points they are fitted to against pinocchio's placements."""

import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import CONFIGS, robot_of

from excite_cli.collision.capsules import fit_capsule
from excite_cli.collision.geometry import link_points, links_with_geometry, world_points
from excite_cli.collision.segments import segment_closest_points
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


def test_a_mesh_in_millimetres_with_its_urdf_scale_gives_a_capsule_in_metres(tmp_path):
    """A 100 mm cube (an STL in mm, as CAD exports them) scaled by 0.001 in the URDF: 10 cm of points,
    not 0.1 mm (coal loads the mesh at its scale; pinocchio keeps the scale beside it)."""
    corners = np.array(np.meshgrid([0, 100], [0, 100], [0, 100])).reshape(3, -1).T.astype(float)
    faces = [
        (0, 1, 3),
        (0, 3, 2),
        (4, 6, 7),
        (4, 7, 5),
        (0, 4, 5),
        (0, 5, 1),
        (2, 3, 7),
        (2, 7, 6),
        (0, 2, 6),
        (0, 6, 4),
        (1, 5, 7),
        (1, 7, 3),
    ]
    facets = "".join(
        "facet normal 0 0 0\nouter loop\n"
        + "".join(f"vertex {x} {y} {z}\n" for x, y, z in corners[list(f)])
        + "endloop\nendfacet\n"
        for f in faces
    )
    (tmp_path / "cube.stl").write_text(f"solid cube\n{facets}endsolid cube\n")
    (tmp_path / "box.urdf").write_text("""<robot name="box"><link name="base"/>
      <link name="arm"><inertial><mass value="1"/>
        <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
        <collision><geometry><mesh filename="cube.stl" scale="0.001 0.001 0.001"/></geometry></collision></link>
      <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="10" velocity="1"/></joint></robot>""")
    config = {"robot": {"urdf": "box.urdf", "active_joints": ["hinge"]}, "limits": {"acceleration": 1.0}}
    (tmp_path / "box.yaml").write_text(yaml.safe_dump(config))
    points, _ = link_points(robot_of(load_problem(tmp_path / "box.yaml"), collision=True), "arm")
    np.testing.assert_allclose(np.ptp(points, axis=0), 0.1, rtol=1e-6)
    radius, start, end = fit_capsule(points)
    assert 0.05 < radius < 0.1
