"""`excite init` on legged robots from their own files, no hand edit: the G1 of example-robot-data (no SRDF:
a searched posture), romeo and iCub (SRDF states), a quadruped carrying an arm (b1 with the Z1: four
soles) and the G1 as MuJoCo Menagerie writes it (a free joint). Each draft is a standing problem that
passes the dry run; its numbers are checked against pinocchio's own kinematics of the full robot, not
excite's: the soles on the drafted floor, the home posture's centre of mass inside the soles' polygon
by the ZMP margin and what a home keeps beyond it."""

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial import ConvexHull

from excite_cli.config_file import load_problem
from excite_cli.drafting.stance import link_points
from excite_cli.dynamics.robot_files import open_source, robot_source
from excite_cli.workflows.init import run_init

G1_MJCF = str(Path(__file__).resolve().parents[2] / "data" / "menagerie_g1" / "g1.xml")
ROBOTS = {
    "g1": ("g1_description/urdf/g1_29dof_rev_1_0.urdf", 2, 7, "searched"),
    "romeo": ("romeo_description/urdf/romeo.urdf", 2, 7, "the state 'half_sitting' of romeo.srdf"),
    "icub": ("icub_description/robots/icub.urdf", 2, 7, "the state 'half_sitting' of icub.srdf"),
    "b1-z1": ("b1_description/urdf/b1-z1.urdf", 4, 6, "the state 'standing_with_arm_up' of b1-z1.srdf"),
    "g1-mjcf": (G1_MJCF, 2, 7, "searched"),
}


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """z of the cross products of rows of 2-D vectors."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


@pytest.mark.parametrize("name", list(ROBOTS))
def test_a_legged_robot_is_drafted_standing_on_its_soles_with_its_arms_moving(tmp_path, name):
    path, soles, arm_joints, posture = ROBOTS[name]
    run = run_init(path, tmp_path / f"{name}.yaml", budget=300.0)
    assert run.plan is not None and not run.draft.problem  # it passes the dry run
    problem = load_problem(run.target)
    robot, zmp = problem.robot, problem.constraints.zmp
    assert robot.floating_base and len(zmp.support_links) == soles
    assert len(robot.active_joints) % arm_joints == 0 and robot.active_joints  # whole arms
    assert posture in run.draft.assumptions["robot.locked_joints"]
    assert set(problem.optimizer.model_fields_set) >= {"restarts", "max_iterations"}  # sized
    source = robot_source(robot, problem.folder) if not path.endswith(".xml") else open_source(Path(path))
    model = source.model()
    q = pin.neutral(model)
    for joint, value in {**robot.locked_joints, **robot.home_posture}.items():
        q[model.idx_qs[model.getJointId(joint)]] = value
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    points = link_points(model, source.geometry(model))
    placed = {
        s: points[s][1] @ data.oMi[points[s][0]].rotation.T + data.oMi[points[s][0]].translation
        for s in zmp.support_links
    }
    floor = problem.constraints.environment.shapes[0].point[2]
    lowest = [p[:, 2].min() for p in placed.values()]
    assert max(lowest) - floor < 1e-3 and min(lowest) - floor > -1e-4  # every sole on the floor
    contact = np.vstack([p[p[:, 2] <= floor + 1e-3, :2] for p in placed.values()])
    hull = contact[ConvexHull(contact).vertices]
    com = pin.centerOfMass(model, data, q)[:2]  # standing still: the ZMP is the centre of mass's projection
    edges = np.roll(hull, -1, axis=0) - hull
    inside = _cross(edges, com - hull) / np.linalg.norm(edges, axis=1)  # counter-clockwise hull: > 0 inside
    cross = _cross(hull, np.roll(hull, -1, axis=0))  # the area centroid (shoelace)
    centroid = ((hull + np.roll(hull, -1, axis=0)) * cross[:, None]).sum(axis=0) / (3 * cross.sum())
    room = min(_cross(edges, centroid - hull) / np.linalg.norm(edges, axis=1))
    assert inside.min() >= zmp.margin + min(0.02, (room - zmp.margin) / 2) - 1e-3
