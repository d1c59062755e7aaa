"""The zero-moment point of the standing G1: equal to the centre of mass's ground projection standing
still, to the ZMP of pinocchio's centroidal dynamics (another algorithm than the base rows of RNEA) in
motion, its Jacobian against finite differences, and the refusals (no floating base, a margin that
leaves no polygon)."""

import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import CONFIGS, assert_refused

from excite_cli.config_file import load_problem, with_overrides
from excite_cli.constraints.support import SupportPolygon
from excite_cli.constraints.zmp import ZeroMomentPoint, zero_moment_point
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import constraint_jacobian_error
from excite_cli.errors import ExciteError

SOLES = ["left_ankle_roll_link", "right_ankle_roll_link"]


@pytest.fixture(scope="module")
def g1():
    excitation = build_excitation(load_problem(CONFIGS / "g1_arms.yaml"))
    return excitation, next(c for c in excitation.constraints if c.name == "zmp")


def test_the_g1_soles_polygon_is_the_bottoms_of_its_eight_contact_spheres(g1):
    _, zmp = g1
    # the URDF's spheres: centres at x −0.05 / 0.12 m and |y| 0.0885 – 0.1485 m from the pelvis, radius 5 mm
    np.testing.assert_allclose(np.sort(np.abs(zmp.polygon.vertices[:, 1])), [0.1435, 0.1435, 0.1485, 0.1485], atol=1e-4)
    np.testing.assert_allclose(np.sort(np.unique(np.round(zmp.polygon.vertices[:, 0], 4))), [-0.05, 0.12], atol=1e-4)
    assert zmp.polygon.height == pytest.approx(-0.7919, abs=1e-4)


def test_standing_still_the_zmp_is_the_centre_of_mass_ground_projection(g1):
    excitation, zmp = g1
    q = excitation.home[None]
    still = zero_moment_point(zmp.wrenches(q, 0 * q, 0 * q), zmp.polygon.height)[0]
    np.testing.assert_allclose(still, excitation.robot.com(excitation.home)[0][:2], atol=1e-12)


def test_in_motion_the_zmp_is_that_of_the_centroidal_momentum_rate(g1):
    """Ground force f = ḣ_lin − m g, moment about the CoM L̇_G (gravity has none there), about the origin
    n_O = L̇_G + c × f: the ZMP of pinocchio's centroidal momentum rate, not of RNEA's base rows."""
    excitation, zmp = g1
    robot = excitation.robot
    alpha = excitation.random_motion(np.random.default_rng(3), 0.9)
    q, qd, qdd = excitation.grid_basis.evaluate(alpha)
    data, mass = robot.model.createData(), sum(i.mass for i in robot.model.inertias)
    expected = []
    for x in zip(q, qd, qdd):
        pin.computeCentroidalMomentumTimeVariation(robot.model, data, *robot.state(*x))
        rate = data.dhg.vector
        f = rate[:3] - mass * robot.model.gravity.linear
        n = rate[3:] + np.cross(data.com[0], f)
        expected.append(np.concatenate([f, n]))
    got = zero_moment_point(zmp.wrenches(q, qd, qdd), zmp.polygon.height)
    np.testing.assert_allclose(got, zero_moment_point(np.array(expected), zmp.polygon.height), atol=1e-10)
    assert np.ptp(got, axis=0).max() > 0.01  # the accelerations move it by centimetres


def test_the_jacobian_matches_finite_differences(g1):
    excitation, zmp = g1
    alpha = excitation.random_start(np.random.default_rng(5))
    assert constraint_jacobian_error(zmp, alpha) < 1e-6
    np.testing.assert_allclose(zmp.values(alpha), zmp.evaluate(alpha)[0], rtol=0, atol=1e-14)


def test_the_fine_check_reports_the_smallest_margin_and_when(g1):
    excitation, zmp = g1
    alpha = excitation.random_start(np.random.default_rng(7))
    check = zmp.check(alpha, excitation.fine_basis)
    q, qd, qdd = excitation.fine_basis.evaluate(alpha)
    margins = zmp.polygon.margins(zero_moment_point(zmp.wrenches(q, qd, qdd), zmp.polygon.height))
    assert check.details["zmp_min_margin_m"] == pytest.approx(margins.min())
    assert check.details["zmp_min_margin_time_s"] == pytest.approx(excitation.fine_basis.time[np.argmin(margins)])
    edges = (zmp.margin - margins.min()) / 0.05  # normalized by 5 cm
    force = -check.details["zmp_min_normal_force_ratio"] / 0.1  # normalized by a tenth of the weight
    assert check.max_violation == pytest.approx(max(edges, force))
    assert 0.9 < check.details["zmp_min_normal_force_ratio"] < 1.0  # the ground carries about the weight


def test_a_margin_wider_than_the_polygon_is_refused(g1):
    excitation, zmp = g1
    with pytest.raises(ExciteError, match="leaves no support polygon") as error:
        ZeroMomentPoint(excitation.robot, excitation.grid_basis, zmp.polygon, 0.09)
    assert error.value.field == "constraints.zmp.margin"


def test_hands_as_soles_are_refused_by_their_field_not_the_margin():
    """Links the arms move cannot be what the robot stands on (the error blamed the margin)."""
    hands = ["left_wrist_yaw_link", "right_wrist_yaw_link"]
    problem = with_overrides(load_problem(CONFIGS / "g1_arms.yaml"), {"constraints.zmp.support_links": hands})
    with pytest.raises(ExciteError, match="'left_wrist_yaw_link' is moved by the active joint") as error:
        build_excitation(problem)
    assert error.value.field == "constraints.zmp.support_links"


def test_a_robot_without_a_floating_base_is_refused(g1):
    problem = load_problem(CONFIGS / "g1_arms.yaml")
    problem = with_overrides(problem, {"robot.floating_base": False, "constraints.com": None})
    with pytest.raises(ExciteError, match="floating_base") as error:
        build_excitation(problem)
    assert error.value.field == "constraints.zmp"


def test_polygon_margins_are_distances_to_the_nearest_edge():
    square = SupportPolygon.from_points(np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]]), 0.0)
    assert len(square.vertices) == 4
    np.testing.assert_allclose(square.margins(np.array([[0.5, 0.5], [0.9, 0.5], [1.2, 0.5]])), [0.5, 0.1, -0.2])
    np.testing.assert_allclose(square.centroid, [0.5, 0.5])
    inner = SupportPolygon.from_points(square.shrunk(0.1), 0.0)
    np.testing.assert_allclose(inner.margins(np.array([[0.5, 0.5], [0.9, 0.5]])), [0.4, 0.0], atol=1e-12)


def test_locked_knees_that_tilt_the_soles_are_blamed_not_the_margin(tmp_path):
    """Issue 102: the G1 with its knees held bent at 0.6 rad (hips and ankles at 0) stands on its heels'
    edges; the refusal named constraints.zmp.margin. The held joints are at fault, and the flat stance
    of the shipped config still builds."""
    data = yaml.safe_load((CONFIGS / "g1_arms.yaml").read_text())
    data["robot"]["locked_joints"] = {"left_knee_joint": 0.6, "right_knee_joint": 0.6}
    data["output"] = str(tmp_path / "out.h5")
    path = tmp_path / "knees.yaml"
    path.write_text(yaml.safe_dump(data))
    line = assert_refused(tmp_path, ["check", str(path)], "robot.locked_joints: at the home posture the soles of")
    assert "'left_ankle_roll_link'" in line and "constraints.zmp.margin 0.02 m leaves no support polygon" in line
    build_excitation(load_problem(CONFIGS / "g1_arms.yaml"))
