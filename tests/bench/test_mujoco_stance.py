"""MuJoCo's standing G1 (its own compilation of the URDF, integrator and soft contacts) against excite's
zero-moment point: the centre of pressure from MuJoCo's contact forces follows the predicted ZMP on a
fast random arm motion, where the centre of mass's projection does not, and MuJoCo's contact points
span excite's support polygon. Held by a joint PD instead of welded, the stance sways away from the
prediction unless its held joints get the feed-forward ``export`` writes for them."""

import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import CONFIGS

from excite_cli.config_file import load_problem
from excite_cli.constraints.zmp import zero_moment_point
from excite_cli.design.held_joints import held_joints
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.errors import ExciteError

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
from mujoco_stance import TIMESTEP, Stance, play_standing, standing_model  # noqa: E402  (a bench module)


@pytest.fixture(scope="module")
def played():
    problem = load_problem(CONFIGS / "g1_arms.yaml")
    excitation = build_excitation(problem)
    zmp = next(c for c in excitation.constraints if c.name == "zmp")
    robot = excitation.robot
    alpha = excitation.random_motion(np.random.default_rng(11), 0.9)
    basis = excitation.trajectory.basis(np.arange(0.0, 4.0, TIMESTEP))  # the first half period
    q, qd, qdd = basis.evaluate(alpha)
    tau = np.array([robot.torques(*x) for x in zip(q, qd, qdd)])
    urdf = resolve_urdf(problem.robot, problem.folder)[0]
    run = play_standing(standing_model(problem, urdf, Stance()), q, qd, tau)
    predicted = zero_moment_point(zmp.wrenches(q, qd, qdd), zmp.polygon.height)
    com = np.array([robot.com(x)[0][:2] for x in q])
    held = held_joints(problem.robot, problem.folder, problem.constraints, robot).torques(q, qd, qdd)
    compliant = {}
    for given in (None, (held.joint_names, held.tau)):
        stance = Stance(1000.0, 40.0, given is not None)
        compliant[stance.feedforward] = play_standing(standing_model(problem, urdf, stance), q, qd, tau, given)
    run = (run, np.abs(run.q - q).max())
    return run, predicted, com, zmp, compliant


def rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


def test_the_centre_of_pressure_follows_the_zero_moment_point(played):
    (run, tracking), predicted, com, _, _ = played
    assert not run.fell and tracking < 0.01 and run.sole_tilt.max() < 0.2
    assert rms(run.cop, predicted) < 0.003  # m
    assert rms(run.cop, com) > 3 * rms(run.cop, predicted)  # the posture alone does not tell
    assert np.ptp(predicted, axis=0).max() > 0.02  # a motion that moves it by centimetres


def test_mujoco_contact_points_span_the_support_polygon_excite_uses(played):
    (run, _), _, _, zmp, _ = played
    ours, theirs = (np.array(sorted(map(tuple, np.round(v, 4)))) for v in (zmp.polygon.vertices, run.polygon.vertices))
    np.testing.assert_allclose(theirs, ours, atol=2e-4)
    np.testing.assert_allclose(run.margin, zmp.polygon.margins(run.cop), atol=2e-4)


def test_links_without_contact_geometry_are_refused():
    problem = load_problem(CONFIGS / "g1_arms.yaml")
    problem.constraints.zmp.support_links = ["torso_link"]
    urdf = resolve_urdf(problem.robot, problem.folder)[0]
    with pytest.raises(ExciteError, match="no sphere, box or capsule"):
        standing_model(problem, urdf, Stance(1000.0, 40.0))


def test_a_pd_stance_given_the_held_joints_feed_forward_follows_the_prediction_where_plain_pd_sways(played):
    """PD 1000 Nm/rad, 40 Nm·s/rad on legs and waist: 13 mm RMS from the rigid prediction alone, 2.3 mm
    with the held joints' feed-forward (measured)."""
    _, predicted, _, _, compliant = played
    plain, fed = (rms(compliant[k].cop, predicted) for k in (False, True))
    assert not compliant[True].fell and fed < 0.004 and plain > 3 * fed
