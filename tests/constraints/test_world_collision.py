"""The world around the robot (issue 19): robot capsules keep a margin from half-spaces, spheres and
capsules fixed in the world. Distances against coal, the Jacobian against central differences on
the Panda, a UR5 and the G1 arms, a home posture inside the world refused by name."""

import coal
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import CONFIGS, assert_refused, constraint_jacobian_error, exported_motion, robot_of, small, smoke_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.collision.capsules import capsule_pairs, capsules_from_config, segment_ends
from excite_cli.collision.geometry import link_points
from excite_cli.collision.world import world_shapes
from excite_cli.config import EnvironmentConfig
from excite_cli.config_file import load_problem
from excite_cli.constraints.world_collision import WorldCollision, distance_bound
from excite_cli.design.resolve import build_excitation

runner = CliRunner()
#: Shapes around each robot (world frame, m): the floor or table plane, a ball, a post.
WORLD = {
    "panda_problem": [
        {"name": "table", "type": "half_space", "point": [0, 0, 0], "normal": [0, 0, 1]},
        {"name": "ball", "type": "sphere", "centre": [0.4, 0.2, 0.6], "radius": 0.1},
        {"name": "post", "type": "capsule", "start": [-0.4, 0.3, 0.0], "end": [-0.4, 0.3, 1.0], "radius": 0.05},
        {"name": "shelf", "type": "box", "centre": [0.45, 0.0, 0.35], "size": [0.3, 0.6, 0.05], "rpy": [0.1, 0.2, 0.3]},
    ],
    "ur5_problem": [
        {"name": "table", "type": "half_space", "point": [0, 0, -0.3], "normal": [0, 0.2, 1]},
        {"name": "ball", "type": "sphere", "centre": [0.3, -0.3, 0.4], "radius": 0.08},
    ],
    "g1_problem": [
        {"name": "floor", "type": "half_space", "point": [0, 0, -0.75], "normal": [0, 0, 1]},  # out of reach
        {"name": "desk", "type": "half_space", "point": [0, 0, -0.1], "normal": [0, 0, 1]},
        {"name": "shelf", "type": "capsule", "start": [0.35, -0.5, 0.1], "end": [0.35, 0.5, 0.1], "radius": 0.03},
    ],
}


def _world(problem, name: str) -> WorldCollision:
    problem.constraints.environment = EnvironmentConfig.model_validate({"shapes": WORLD[name]})
    excitation = build_excitation(problem)
    return excitation, next(c for c in excitation.constraints if isinstance(c, WorldCollision))


@pytest.mark.parametrize("name", list(WORLD))
def test_the_world_distance_jacobian_matches_central_differences(request, name):
    problem = small(request.getfixturevalue(name), harmonics=3)
    problem.trajectory.constraint_period = 0.2
    excitation, constraint = _world(problem, name)
    alpha = excitation.limits.random_start(excitation.trajectory.n_coefficients, np.random.default_rng(5), 0.9)
    g = constraint.evaluate(alpha)[0]
    assert g.shape == (len(constraint.pairs),) and len(constraint.pairs) > 0
    assert constraint_jacobian_error(constraint, alpha) <= 1e-6


def _coal_capsule(start: np.ndarray, end: np.ndarray, radius: float) -> tuple[coal.Capsule, coal.Transform3s]:
    """A coal capsule (along its local z, centred) on the segment [start, end] [m]."""
    axis, length = end - start, np.linalg.norm(end - start)
    rotation = (
        np.eye(3) if length == 0 else pin.Quaternion.FromTwoVectors(np.array([0, 0, 1.0]), axis / length).matrix()
    )
    return coal.Capsule(radius, float(np.linalg.norm(axis))), coal.Transform3s(rotation, (start + end) / 2)


def _coal_distance(shape: dict, capsule: tuple) -> float:
    if shape["type"] == "half_space":
        normal = np.asarray(shape["normal"], float) / np.linalg.norm(shape["normal"])
        world, placement = coal.Halfspace(normal, float(normal @ shape["point"])), coal.Transform3s()
    elif shape["type"] == "sphere":
        world, placement = coal.Sphere(shape["radius"]), coal.Transform3s(np.eye(3), np.asarray(shape["centre"], float))
    elif shape["type"] == "box":
        rotation = pin.rpy.rpyToMatrix(*shape["rpy"])
        world, placement = coal.Box(*shape["size"]), coal.Transform3s(rotation, np.asarray(shape["centre"], float))
    else:
        world, placement = _coal_capsule(
            np.asarray(shape["start"], float), np.asarray(shape["end"], float), shape["radius"]
        )
    result = coal.DistanceResult()
    coal.distance(world, placement, *capsule, coal.DistanceRequest(), result)
    return result.min_distance


def test_the_world_distances_are_coal_s(panda_problem):
    """At 20 random postures, every (capsule, shape) distance that coal finds positive is the
    closed form's to 1e-9 m (coal's half-space distance is not a distance once they overlap)."""
    excitation, constraint = _world(panda_problem, "panda_problem")
    q = excitation.robot.random_states(20, np.random.default_rng(2))[0]
    closed = constraint._closest(q)[0]
    start, end, _, _ = segment_ends(constraint.kinematics, constraint.capsules, q)
    compared = 0
    for t in range(q.shape[0]):
        for k, (c, s) in enumerate(constraint.pairs):
            capsule = _coal_capsule(start[:, t, c], end[:, t, c], constraint.capsules[c].radius)
            if WORLD["panda_problem"][s]["type"] == "box":  # coal gives it in the constraint too
                continue
            reference = _coal_distance(WORLD["panda_problem"][s], capsule)
            if reference > 0:
                assert closed[t, k] == pytest.approx(reference, abs=1e-9)
                compared += 1
    assert compared > 300


@pytest.mark.parametrize("name", ["panda_problem", "g1_problem"])
def test_the_distance_bound_is_below_every_distance_and_leaves_out_what_is_out_of_reach(request, name):
    """distance_bound of every (moving capsule, shape) against the distances at 300 random postures
    within the joint limits (coal; the half-space's height by hand); the pairs it leaves out are
    those whose bound is above the margin (the G1's floor)."""
    problem = request.getfixturevalue(name)
    excitation, constraint = _world(problem, name)
    robot, shapes = excitation.robot, world_shapes(problem.constraints.environment)
    capsules = constraint.capsules
    bounds = np.array([[distance_bound(robot, c, s) for s in shapes] for c in capsules])
    assert {(c, s) for c, s in zip(*np.nonzero(bounds <= 0.02))} == set(constraint.pairs)
    q = robot.random_states(300, np.random.default_rng(4))[0]
    start, end, _, _ = segment_ends(constraint.kinematics, capsules, q)
    for t in range(q.shape[0]):
        for c, capsule in enumerate(capsules):
            placed = _coal_capsule(start[:, t, c], end[:, t, c], capsule.radius)
            for s, spec in enumerate(WORLD[name]):
                if spec["type"] == "half_space":
                    height = min(spec["normal"] @ (x[:, t, c] - spec["point"]) for x in (start, end))
                    distance = height / np.linalg.norm(spec["normal"]) - capsule.radius
                else:
                    distance = _coal_distance(spec, placed)
                assert distance >= bounds[c, s] - 1e-12
    if name == "g1_problem":
        assert bounds[:, 0].min() > 0.5  # the floor, 75 cm below the pelvis


def test_the_shipped_g1_keeps_its_floor_out_of_reach_and_optimizes_as_without_it(g1_problem):
    assert [s.name for s in g1_problem.constraints.environment.shapes] == ["floor"]
    with_floor = build_excitation(g1_problem)
    g1_problem.constraints.environment = None
    assert [c.name for c in with_floor.constraints] == [c.name for c in build_excitation(g1_problem).constraints]


def test_capsules_no_active_joint_moves_are_left_out(panda_problem):
    _, constraint = _world(panda_problem, "panda_problem")
    links = {c.link for c in constraint.capsules}
    assert "panda_link0" not in links and {"panda_link1", "panda_hand"} <= links


def test_a_home_posture_inside_the_world_stops_before_optimizing_naming_link_and_shape(tmp_path):
    config = smoke_config(tmp_path)
    config["constraints"] = {
        "environment": {"shapes": [{"name": "shelf", "type": "half_space", "point": [0, 0, 0.5], "normal": [0, 0, 1]}]}
    }
    (tmp_path / "low.yaml").write_text(yaml.safe_dump(config))
    assert_refused(tmp_path, ["optimize", str(tmp_path / "low.yaml")], "constraints.environment: violated before")
    assert_refused(tmp_path, ["optimize", str(tmp_path / "low.yaml")], "cm from shelf")


@pytest.mark.parametrize(
    "shape, expected",
    [
        ({"name": "ball", "type": "sphere", "centre": [0, 0, 1]}, "a sphere needs radius"),
        ({"name": "wall", "type": "half_space", "point": [0, 0, 0], "normal": [0, 0, 0]}, "must not be zero"),
        ({"name": "box", "type": "box", "centre": [0, 0, 1]}, "a box needs size"),
        ({"name": "cone", "type": "cone", "centre": [0, 0, 1]}, "constraints.environment.shapes.0.type"),
    ],
)
def test_a_world_shape_that_cannot_be_is_refused(tmp_path, shape, expected):
    config = smoke_config(tmp_path)
    config["constraints"] = {"environment": {"shapes": [shape]}}
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(config))
    assert_refused(tmp_path, ["optimize", str(tmp_path / "bad.yaml")], expected)


@pytest.mark.end_to_end
@pytest.mark.parametrize("config", ["panda.yaml", "ur5.yaml"])
def test_a_lab_arm_plays_above_its_table_apart_from_itself_and_within_its_torques(tmp_path, config):
    """The shipped lab arms (configs/panda.yaml, configs/ur5.yaml) with a short optimization,
    exported at 1 kHz: at every sample (transitions included) every moving capsule keeps its margin
    above the table and every checked pair its own, by pinocchio's forward kinematics and coal, and
    |τ| ≤ the URDF's effort by pinocchio's RNEA, all computed here from the exported q, q̇, q̈."""
    config = yaml.safe_load((CONFIGS / config).read_text())
    config["optimizer"] = {"max_iterations": 60, "restarts": 1, "workers": 1}
    config["sequence"]["iterations"] = 1
    config["output"] = str(tmp_path / "lab.h5")
    (tmp_path / "lab.yaml").write_text(yaml.safe_dump(config))
    problem = load_problem(tmp_path / "lab.yaml")
    assert runner.invoke(app, ["optimize", str(tmp_path / "lab.yaml")]).exit_code == 0
    played = tmp_path / "lab.csv"
    assert runner.invoke(app, ["export", str(tmp_path / "lab.h5"), "-o", str(played), "--rate", "1000"]).exit_code == 0
    q, qd, qdd = exported_motion(played, problem.robot.active_joints)
    robot = robot_of(problem, collision=True)
    (table,) = problem.constraints.environment.shapes
    world = [c for c in capsules_from_config(problem.constraints.environment, robot) if _moves(robot, c)]
    capsules = capsules_from_config(problem.constraints.self_collision, robot)
    pairs = capsule_pairs(problem.constraints.self_collision, robot, capsules)
    model, data = robot.model, robot.model.createData()
    heights, gaps, use = [], [], []
    shapes = [coal.Capsule(c.radius, float(np.linalg.norm(c.end - c.start))) for c in capsules]
    for t in range(q.shape[0]):
        pin.forwardKinematics(model, data, robot.state(q[t], qd[t], qdd[t])[0])
        place = [(data.oMi[c.joint].act(c.start), data.oMi[c.joint].act(c.end)) for c in world]
        heights.append([min(a[2], b[2]) - c.radius for (a, b), c in zip(place, world)])
        if t % 10 == 0:  # coal on every 10th sample: 100 Hz, the pairs move < 2 mm between them
            ends = [(data.oMi[c.joint].act(c.start), data.oMi[c.joint].act(c.end)) for c in capsules]
            placed = [_coal_capsule(a, b, c.radius)[1] for (a, b), c in zip(ends, capsules)]
            gaps.append(min(_pair_distance(shapes, placed, i, j) for i, j in pairs))
        tau = pin.rnea(model, data, *robot.state(q[t], qd[t], qdd[t]))[robot.v_idx]
        use.append(np.abs(tau) / model.effortLimit[robot.v_idx])
    assert table.normal == (0, 0, 1) and table.point == (0, 0, 0)
    assert np.min(heights) >= table.margin and np.min(gaps) >= problem.constraints.self_collision.margin
    assert np.max(use) <= 1.0


def test_the_shipped_ur5_capsules_cover_every_vertex_of_its_collision_meshes():
    """configs/ur5.yaml gives its capsules (the fitted ones reach below the mounting plane): every
    vertex of every moving link's URDF collision mesh lies inside one of that link's capsules."""
    problem = load_problem(CONFIGS / "ur5.yaml")
    robot = robot_of(problem, collision=True)
    capsules = capsules_from_config(problem.constraints.self_collision, robot)
    for link in {c.link for c in capsules}:
        points, _ = link_points(robot, link)
        inside = [_segment_distance(points, c.start, c.end) - c.radius for c in capsules if c.link == link]
        assert np.min(inside, axis=0).max() <= 0.0, link


def test_ignored_links_leave_out_given_capsules_too():
    problem = load_problem(CONFIGS / "ur5.yaml")
    robot = robot_of(problem, collision=True)
    world = capsules_from_config(problem.constraints.environment, robot, "constraints.environment")
    assert {c.link for c in world} == {c.link for c in problem.constraints.environment.capsules} - {"shoulder_link"}
    assert "shoulder_link" in {c.link for c in capsules_from_config(problem.constraints.self_collision, robot)}


def _segment_distance(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """(k,) distances [m] of ``points`` (k, 3) from the segment [start, end]."""
    axis = end - start
    t = np.clip((points - start) @ axis / (axis @ axis), 0.0, 1.0)
    return np.linalg.norm(points - start - np.outer(t, axis), axis=1)


def _moves(robot, capsule) -> bool:
    """Whether an active joint carries the capsule's link (pinocchio's joint supports)."""
    return any(robot.model.idx_vs[j] in robot.v_idx for j in robot.model.supports[capsule.joint] if j > 0)


def _pair_distance(shapes: list, placed: list, i: int, j: int) -> float:
    result = coal.DistanceResult()
    coal.distance(shapes[i], placed[i], shapes[j], placed[j], coal.DistanceRequest(), result)
    return result.min_distance
