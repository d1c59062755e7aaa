"""Which problem a starting config drafts for a legged robot (a standing one, or a fixed base and why), and
what it holds: the G1 as MuJoCo Menagerie writes it (its free joint) and the G1 of example-robot-data."""

from pathlib import Path

import pytest

from excite_cli.drafting.stance import find_stance
from excite_cli.drafting.standing import ZMP_MARGIN, StandOptions, stance_for, standing_choice, zmp_margin
from excite_cli.dynamics.robot_files import open_source
from excite_cli.errors import ExciteError

G1_MJCF = Path(__file__).resolve().parents[2] / "data" / "menagerie_g1" / "g1.xml"


@pytest.fixture(scope="module")
def g1():
    source = open_source(G1_MJCF)
    return source, source.model()


def test_a_free_joint_is_a_standing_robot_not_a_welded_one(g1):
    source, model = g1
    stance, why = stance_for(source, model, StandOptions(), True)
    assert why.startswith("a standing robot: the file's free joint 'floating_base_joint', standing on ")
    assert stance.soles == ["left_ankle_roll_link", "right_ankle_roll_link"]
    assert [arm[0] for arm in stance.arms] == ["left_shoulder_pitch_joint", "right_shoulder_pitch_joint"]


def test_a_fixed_base_says_it_welded_the_free_joint(g1):
    source, model = g1
    assert stance_for(source, model, StandOptions(stand=False), True) == (
        None,
        "a fixed base, as asked; the file's free joint 'floating_base_joint' welded",
    )
    assert stance_for(source, model, StandOptions(), False) == (
        None,
        "a fixed base: no collision geometry read, so no soles to stand on; the file's free joint "
        "'floating_base_joint' welded",
    )
    with pytest.raises(ExciteError, match="stand: a standing robot needs its soles' collision geometry"):
        stance_for(source, model, StandOptions(stand=True), False)


def test_the_held_joints_stand_and_the_arms_move(g1):
    source, model = g1
    stance = find_stance(source, model, source.geometry(model), None, None)
    choice = standing_choice(stance, None, model)
    assert len(choice.active) == 14 and all("shoulder" in j or "elbow" in j or "wrist" in j for j in choice.active)
    assert set(choice.held) == {n for n in stance.posture if n not in choice.active}  # legs and waist
    assert choice.held["left_knee_joint"] == round(stance.posture["left_knee_joint"], 4) > 0.2  # bent
    given = standing_choice(stance, ["waist_yaw_joint"], model)
    assert given.active == ["waist_yaw_joint"] and "left_shoulder_pitch_joint" in given.held
    with pytest.raises(ExciteError, match="joints: 'elbow' is not a 1-DoF joint"):
        standing_choice(stance, ["elbow"], model)


def test_the_zmp_margin_is_two_centimetres_or_two_thirds_of_small_soles_room(g1):
    source, model = g1
    stance = find_stance(source, model, source.geometry(model), None, None)
    assert stance.room > 2 * ZMP_MARGIN and zmp_margin(stance) == ZMP_MARGIN
    stance.room = 0.031  # iCub's
    assert zmp_margin(stance) == 0.02
    stance.room = 0.024
    assert zmp_margin(stance) == 0.016
