"""MuJoCo's standing G1 (its own compilation of the URDF, integrator and soft contacts) against excite's
zero-moment point: the centre of pressure from MuJoCo's contact forces follows the predicted ZMP on a
fast random arm motion, where the centre of mass's projection does not, and MuJoCo's contact points
span excite's support polygon."""

import numpy as np
import pytest
from conftest import CONFIGS

from excite_cli.config_file import load_problem
from excite_cli.constraints.zmp import zero_moment_point
from excite_cli.design.mujoco_stance import TIMESTEP, Stance, play_standing, standing_model
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.urdf_source import resolve_urdf
from excite_cli.errors import ExciteError


@pytest.fixture(scope="module")
def played():
    problem = load_problem(CONFIGS / "g1_arms.yaml")
    excitation = build_excitation(problem)
    zmp = next(c for c in excitation.constraints if c.name == "zmp")
    robot, locked = excitation.robot, dict(problem.robot.locked_joints)
    alpha = excitation.random_motion(np.random.default_rng(11), 0.9)
    basis = excitation.trajectory.basis(np.arange(0.0, 4.0, TIMESTEP))  # the first half period
    q, qd, qdd = basis.evaluate(alpha)
    tau = np.array([robot.torques(*x) for x in zip(q, qd, qdd)])
    urdf = resolve_urdf(problem.robot, problem.folder)[0]
    model = standing_model(urdf, robot.joint_names, locked, problem.constraints.zmp.support_links, Stance())
    run = play_standing(model, robot.joint_names, locked, q, qd, tau)
    predicted = zero_moment_point(zmp.wrenches(q, qd, qdd), zmp.polygon.height)
    com = np.array([robot.com(x)[0][:2] for x in q])
    return run, predicted, com, zmp


def rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


def test_the_centre_of_pressure_follows_the_zero_moment_point(played):
    run, predicted, com, _ = played
    assert not run.fell and run.tracking.max() < 0.01 and run.tilt_deg.max() < 0.2
    assert rms(run.cop, predicted) < 0.003  # m
    assert rms(run.cop, com) > 3 * rms(run.cop, predicted)  # the posture alone does not tell
    assert np.ptp(predicted, axis=0).max() > 0.02  # a motion that moves it by centimetres


def test_mujoco_contact_points_span_the_support_polygon_excite_uses(played):
    run, _, _, zmp = played
    ours, theirs = (np.array(sorted(map(tuple, np.round(v, 4)))) for v in (zmp.polygon.vertices, run.polygon.vertices))
    np.testing.assert_allclose(theirs, ours, atol=2e-4)
    np.testing.assert_allclose(run.margin, zmp.polygon.margins(run.cop), atol=2e-4)


def test_links_without_contact_geometry_are_refused():
    problem = load_problem(CONFIGS / "g1_arms.yaml")
    urdf = resolve_urdf(problem.robot, problem.folder)[0]
    with pytest.raises(ExciteError, match="no sphere, box or capsule"):
        standing_model(urdf, list(problem.robot.active_joints), {}, ["torso_link"], Stance(1000.0, 40.0))
