"""The joints a starting config moves: every revolute joint that follows no other, prismatic and
mimic joints held inside their limits; given joints checked by name."""

import pytest
from conftest import GOOD, PENDULUM

from excite_cli.drafting.starting_config import StartingConfig, draft_config, joint_choice
from excite_cli.dynamics.urdf_source import example_robot_data_root
from excite_cli.errors import ExciteError

PANDA = example_robot_data_root() / "example-robot-data" / "robots" / "panda_description" / "urdf" / "panda.urdf"


def test_revolute_joints_move_and_the_fingers_are_held():
    draft = StartingConfig({})
    active, held = joint_choice(PANDA, None, draft)
    assert active == [f"panda_joint{k}" for k in range(1, 8)]
    assert held == {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}  # prismatic (and a mimic)
    assert "prismatic ones are held" in draft.assumptions["robot.active_joints"]


def test_given_joints_are_checked_by_name_and_the_others_held_inside_their_limits():
    active, held = joint_choice(PANDA, ["panda_joint1", "panda_joint2"], StartingConfig({}))
    assert active == ["panda_joint1", "panda_joint2"] and "panda_joint2" not in held
    assert held["panda_joint3"] == 0.0
    assert held["panda_joint4"] == pytest.approx(-0.0698)  # 0 is outside its URDF range [-3.0718, -0.0698]
    with pytest.raises(ExciteError, match="'panda_hand' is not a 1-DoF joint"):
        joint_choice(PANDA, ["panda_hand"], StartingConfig({}))


def test_a_joint_the_urdf_gives_no_range_is_named(tmp_path):
    """The double pendulum of example-robot-data has lower = upper = 0: it was refused as 'position_margin:
    0 rad leaves no range', far from the cause."""
    urdf = tmp_path / "still.urdf"
    urdf.write_text(PENDULUM.format(**{**GOOD, "mimic": "", "lower": "2.0"}))  # upper is 2.0 too
    with pytest.raises(ExciteError, match="the URDF gives hinge no position range"):
        draft_config({"urdf": "still.urdf", "source": "file"}, urdf, [str(tmp_path)], ["hinge"], tmp_path / "s.yaml")
