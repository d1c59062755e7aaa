"""The joints a starting config moves: every revolute joint that follows no other, prismatic and
mimic joints held inside their limits, a gripper's joints held (found where the chain branches, or by
name), continuous joints given one turn each way; given joints checked by name."""

import pytest
from conftest import chain_urdf

from excite_cli.drafting.joints import CONTINUOUS_RANGE, joint_choice
from excite_cli.dynamics.robot_files import example_robot_data_root, open_source
from excite_cli.errors import ExciteError

ROBOTS = example_robot_data_root() / "example-robot-data" / "robots"
PANDA = ROBOTS / "panda_description" / "urdf" / "panda.urdf"
G1 = ROBOTS / "g1_description" / "urdf" / "g1_29dof_rev_1_0.urdf"


def test_revolute_joints_move_and_the_fingers_are_held():
    choice = joint_choice(open_source(PANDA), None, open_source(PANDA).model())
    assert choice.active == [f"panda_joint{k}" for k in range(1, 8)]
    assert choice.held == {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}  # prismatic (and a mimic)
    assert "prismatic ones are held" in choice.assumptions["robot.active_joints"]
    assert choice.ranges == {}


def test_given_joints_are_checked_by_name_and_the_others_held_inside_their_limits():
    choice = joint_choice(open_source(PANDA), ["panda_joint1", "panda_joint2"], open_source(PANDA).model())
    assert choice.active == ["panda_joint1", "panda_joint2"] and "panda_joint2" not in choice.held
    assert choice.held["panda_joint3"] == 0.0
    assert choice.held["panda_joint4"] == pytest.approx(-0.0698)  # 0 is outside its URDF range [-3.0718, -0.0698]
    with pytest.raises(ExciteError, match="'panda_hand' is not a 1-DoF joint"):
        joint_choice(open_source(PANDA), ["panda_hand"], open_source(PANDA).model())


def test_a_gripper_finger_on_a_revolute_joint_is_held_not_made_an_arm_joint(tmp_path):
    """The Gen3 lite's right finger is a revolute joint that follows no other: it became the 7th arm joint."""
    path = tmp_path / "gen3_lite.urdf"
    path.write_text(chain_urdf(["revolute"] * 6))
    choice = joint_choice(open_source(path), None, open_source(path).model())
    assert choice.active == [f"joint_{k}" for k in range(1, 7)]
    assert "right_finger_bottom_joint" in choice.held and len(choice.held) == 4
    said = choice.assumptions["robot.active_joints"]
    assert "held as a gripper's, a hand's or a mobile base's: " in said and "right_finger_bottom_joint" in said
    given = joint_choice(open_source(path), ["joint_1", "right_finger_bottom_joint"], open_source(path).model())
    assert given.active == ["joint_1", "right_finger_bottom_joint"]  # named: moved


def test_a_finger_named_as_one_is_held_where_the_chain_does_not_branch(tmp_path):
    path = tmp_path / "one_finger.urdf"
    path.write_text(chain_urdf(["revolute"] * 4, gripper=False).replace('"joint_4"', '"gripper_joint"'))
    choice = joint_choice(open_source(path), None, open_source(path).model())
    assert choice.active == ["joint_1", "joint_2", "joint_3"] and list(choice.held) == ["gripper_joint"]


def test_a_humanoid_branching_at_its_pelvis_keeps_every_revolute_joint():
    choice = joint_choice(open_source(G1), None, open_source(G1).model())
    assert len(choice.active) == 29 and choice.held == {}


def test_continuous_joints_move_within_one_turn_each_way(tmp_path):
    """Kinova's Gen3 has continuous joints 1, 3, 5 and 7: 3 of its 7 joints moved."""
    path = tmp_path / "gen3.urdf"
    path.write_text(chain_urdf(["continuous", "revolute"] * 3 + ["continuous"], gripper=False))
    model = open_source(path).model()
    assert model.nq == 7  # one angle each, not (cos, sin)
    choice = joint_choice(open_source(path), None, model)
    assert choice.active == [f"joint_{k}" for k in range(1, 8)]
    assert choice.ranges == {f"joint_{k}": CONTINUOUS_RANGE for k in (1, 3, 5, 7)}
    assert "narrow it to what the cables allow" in choice.assumptions["robot.joint_ranges"]


def test_a_mobile_manipulators_hand_and_wheels_are_held():
    """Tiago: its hand's 30 joints and its wheels (continuous) were among the 45 active joints."""
    path = ROBOTS / "tiago_description" / "robots" / "tiago.urdf"
    choice = joint_choice(open_source(path), None, open_source(path).model())
    assert choice.active == [f"arm_{k}_joint" for k in range(1, 8)] + ["head_1_joint", "head_2_joint"]
    assert {"wheel_left_joint", "wheel_right_joint", "hand_index_flex_1_joint"} <= set(choice.held)
    assert choice.ranges == {}  # the continuous wheels are held, not given a range
