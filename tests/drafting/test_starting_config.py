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


def test_no_home_posture_names_the_joints_it_chose_and_what_to_give(tmp_path):
    """The pendulum held away from hanging (lower limit 0.5 rad) with 0.01 Nm efforts: gravity exceeds
    the torque limits at every posture at rest."""
    urdf = tmp_path / "weak.urdf"
    urdf.write_text(
        PENDULUM.format(**{**GOOD, "mimic": "", "lower": "0.5"})
        .replace('effort="20"', 'effort="0.01"')
        .replace('effort="5"', 'effort="0.01"')
    )
    with pytest.raises(
        ExciteError, match="with the 2 active joints hinge, tip_joint: .*the joints to move named"
    ) as caught:
        draft_config({"urdf": "weak.urdf", "source": "file"}, urdf, [str(tmp_path)], None, tmp_path / "weak.yaml")
    assert "clearance" not in str(caught.value)  # no capsule: no clearance to speak of
