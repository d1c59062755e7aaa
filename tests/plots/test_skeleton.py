"""The skeleton drawn in the posture strip: joint origins against the robots' own geometry."""

import numpy as np
import pinocchio as pin
from conftest import CONFIGS, robot_of, write_config

from excite_cli.config_file import load_problem
from excite_cli.dynamics.robot_files import example_robot_data_root
from excite_cli.plots.skeleton import skeleton


def test_skeleton_of_the_panda_at_zero_reaches_the_flange():
    robot = robot_of(load_problem(CONFIGS / "panda_joint_limits.yaml"))
    points = skeleton(robot, np.zeros(7)).reshape(-1, 3)
    # Panda kinematics at q = 0 (Franka's DH table): flange at x = 0.088 m, z = 0.333 + 0.316 + 0.384 − 0.107 m
    assert np.min(np.linalg.norm(points - [0.088, 0.0, 0.926], axis=1)) < 1e-6
    assert np.min(np.linalg.norm(points - [0.0825, 0.0, 0.649], axis=1)) < 1e-6


def test_skeleton_of_the_g1_has_its_locked_legs(g1_problem):
    robot = robot_of(g1_problem)
    points = skeleton(robot, robot.home).reshape(-1, 3)
    lengths = np.linalg.norm(np.diff(skeleton(robot, robot.home), axis=1)[:, 0], axis=1)
    # the soles are ~0.79 m below the pelvis (the floating base at the origin); legs are locked joints
    assert points[:, 2].min() < -0.7 and np.count_nonzero(lengths > 0.1) >= 8


def test_a_joint_and_a_link_of_one_name_draw_the_joint(tmp_path):
    """so100's "gripper" is a joint and a link: the skeleton takes the joint's frame, as pinocchio places it."""
    urdf = "so_arm_description/urdf/so100.urdf"
    joints = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]
    robot_section = {"urdf": urdf, "source": "example-robot-data", "active_joints": joints}
    config = {"robot": robot_section, "limits": {"acceleration": 1}}
    robot = robot_of(load_problem(write_config(tmp_path, config)), collision=True)
    q = np.array([0.3, 1.0, -1.0, 0.5, 0.2, 0.8])
    points = skeleton(robot, q).reshape(-1, 3)
    model = pin.buildModelFromUrdf(str(example_robot_data_root() / "example-robot-data" / "robots" / urdf))
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    gripper = data.oMi[model.getJointId("gripper")].translation
    assert np.min(np.linalg.norm(points - gripper, axis=1)) < 1e-9
