"""CoM region (Eq. 52) and capsule self-collision (Eq. 53): Jacobians against finite differences,
exact distances against coal, capsule fitting, and problems infeasible before optimization."""

import coal
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import CONFIGS, TESTS, write_config

from excite_cli.collision.capsules import capsule_frames, segment_ends
from excite_cli.collision.segments import segment_closest_points
from excite_cli.config_file import load_problem
from excite_cli.constraints.self_collision import SelfCollision
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import constraint_jacobian_error
from excite_cli.errors import ExciteError

HERE = TESTS


def _g1(tmp_path, **edits):
    data = yaml.safe_load((CONFIGS / "g1_arms.yaml").read_text())
    data["trajectory"].update(harmonics=3, cost_samples=10, cost_period=0.8, constraint_period=0.1)
    for section, values in edits.items():
        data["constraints"][section].update(values)
    return build_excitation(load_problem(write_config(tmp_path, data)))


@pytest.fixture(scope="module")
def g1(tmp_path_factory):
    return _g1(tmp_path_factory.mktemp("g1"))


@pytest.fixture(scope="module")
def panda():
    return build_excitation(load_problem(HERE / "panda_capsules.yaml"))


def _lively(excitation, seed):
    """A start that moves a lot: the joint-limit start at 90 % fill, not shrunk for the others."""
    return excitation.limits.random_start(
        excitation.trajectory.n_coefficients, np.random.default_rng(seed), 0.9, excitation.home
    )


@pytest.mark.parametrize("name", ["com_region", "self_collision"])
def test_g1_constraint_jacobians_match_finite_differences(g1, name):
    constraint = next(c for c in g1.constraints if c.name == name)
    assert constraint_jacobian_error(constraint, _lively(g1, 1)) < 1e-6


def test_panda_capsule_jacobian_matches_finite_differences(panda):
    constraint = panda.constraints[1]
    alpha = _lively(panda, 2)
    g, _ = constraint.evaluate(alpha)
    assert g.size == 6 and g.max() > -1.0  # some pair comes close, so the test means something
    assert constraint_jacobian_error(constraint, alpha) < 1e-6


@pytest.mark.parametrize("robot", ["panda", "g1"])
def test_closed_form_distances_and_witness_points_equal_coal(robot, request):
    excitation = request.getfixturevalue(robot)
    constraint = excitation.constraints[-1]
    assert isinstance(constraint, SelfCollision)
    Q = excitation.grid_basis.q @ _lively(excitation, 3).T
    d = constraint.distances(Q)
    start, end = segment_ends(constraint.kinematics, constraint.capsules, Q)[:2]
    first, second = [i for i, _ in constraint.pairs], [j for _, j in constraint.pairs]
    c1, c2 = segment_closest_points(start[..., first], end[..., first], start[..., second], end[..., second])
    normal = (c2 - c1) / np.linalg.norm(c2 - c1, axis=0)
    alpha = _lively(excitation, 3)
    assert np.array_equal(constraint.values(alpha), constraint.evaluate(alpha)[0])  # values alone: the same g
    rotations, centres = capsule_frames(*constraint.kinematics.placements(Q), constraint.capsules)
    radii = np.array([c.radius for c in constraint.capsules])
    for t in range(0, d.shape[0], 7):
        for p, (i, j) in enumerate(constraint.pairs):
            exact = constraint._distance(rotations, centres, t, p)
            assert d[t, p] == pytest.approx(exact.min_distance, abs=1e-9)
            np.testing.assert_allclose(c1[:, t, p] + radii[i] * normal[:, t, p], exact.getNearestPoint1(), atol=1e-6)
            np.testing.assert_allclose(
                c1[:, t, p] + (d[t, p] + radii[i]) * normal[:, t, p], exact.getNearestPoint2(), atol=1e-6
            )


def test_com_region_holds_at_home_and_fails_when_too_small(g1, tmp_path):
    com = next(c for c in g1.constraints if c.name == "com_region")
    check = com.check(g1.static(), g1.grid_basis)
    assert check.details["com_max_excursion_m"] < 0.002
    with pytest.raises(ExciteError, match=r"constraints.com: .*CoM 0\.\d+ cm from the support centre"):
        _g1(tmp_path, com={"radius": 0.0005})


def test_support_centre_comes_from_the_soles(g1):
    com = next(c for c in g1.constraints if c.name == "com_region")
    # G1 soles: contact spheres from x = -0.05 to 0.12 m below the ankles, so the centre is ~3.5 cm ahead
    assert com.centre[0] == pytest.approx(0.0355, abs=0.002) and abs(com.centre[1]) < 1e-6


def test_colliding_pair_at_home_is_named(tmp_path):
    with pytest.raises(ExciteError, match=r"constraints.self_collision: .*torso_link–left_shoulder_yaw_link"):
        _g1(tmp_path, self_collision={"exclude_pairs": [["torso_link", "left_shoulder_roll_link"]]})


def test_capsules_follow_the_links(panda):
    constraint = panda.constraints[1]
    q = panda.home[None]
    rotations, centres = capsule_frames(*constraint.kinematics.placements(q), constraint.capsules)
    robot = panda.robot
    pin.forwardKinematics(robot.model, robot.data, robot.state(q[0], 0 * q[0], 0 * q[0])[0])
    pin.updateFramePlacements(robot.model, robot.data)
    hand = robot.data.oMf[robot.model.getFrameId("panda_hand")]
    # the hand capsule runs from the hand frame origin 0.1 m along its z axis
    np.testing.assert_allclose(centres[0, 3], hand.act(np.array([0, 0, 0.05])), atol=1e-12)
    np.testing.assert_allclose(rotations[0, 3][:, 2], hand.rotation[:, 2], atol=1e-12)
    assert isinstance(constraint._shapes[3], coal.Capsule)
