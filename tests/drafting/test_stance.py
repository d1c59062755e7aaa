"""How a robot stands, from its files alone: the legs, arms and soles of humanoids and a quadruped carrying
an arm from example-robot-data, a standing posture from the SRDF (levelled where its soles are tilted) or
searched (checked with pinocchio's forward kinematics and centre of mass, not excite's), and an arm that
stands on no legs."""

import numpy as np
import pinocchio as pin
import pytest

from excite_cli.drafting.posture_search import KNEE_DROP, SOLE_HEIGHT
from excite_cli.drafting.stance import find_stance, link_points
from excite_cli.dynamics.robot_files import example_robot_data_root, open_source
from excite_cli.dynamics.urdf_meshes import package_folders
from excite_cli.errors import ExciteError

SHARE = example_robot_data_root()
ROBOTS = SHARE / "example-robot-data" / "robots"


def _stance(path: str, posture=None, soles=None):
    urdf = ROBOTS / path
    source = open_source(urdf, package_folders(urdf, [str(SHARE)]))
    model = source.model()
    geometry = source.geometry(model)
    return find_stance(source, model, geometry, posture, soles), model, geometry


def _soles_at(model, geometry, stance, values: dict) -> dict:
    """{sole: (k, 3) its collision points [m] within SOLE_HEIGHT of its lowest at the zero posture, placed at
    ``values`` by pinocchio}."""
    points = link_points(model, geometry)
    placed = {}
    for q in (pin.neutral(model), _vector(model, values)):
        data = model.createData()
        pin.forwardKinematics(model, data, q)
        placed[len(placed)] = {
            s: points[s][1] @ data.oMi[points[s][0]].rotation.T + data.oMi[points[s][0]].translation
            for s in stance.soles
        }
    zero, there = placed[0], placed[1]
    return {s: there[s][zero[s][:, 2] <= zero[s][:, 2].min() + SOLE_HEIGHT] for s in stance.soles}


def _rise(model, geometry, stance) -> np.ndarray:
    """How far each sole contact point is above where it is at the zero posture [m] (one value: flat as there)."""
    there, zero = _soles_at(model, geometry, stance, stance.posture), _soles_at(model, geometry, stance, {})
    return np.concatenate([there[s][:, 2] - zero[s][:, 2] for s in stance.soles])


def _vector(model, values: dict) -> np.ndarray:
    q = pin.neutral(model)
    for name, value in values.items():
        q[model.idx_qs[model.getJointId(name)]] = value
    return q


def test_a_full_size_humanoid_stands_in_its_srdf_state_on_its_ankle_meshes():
    """Talos: its sole frame has no geometry, its ankle link's mesh is the sole; the arms end in grippers
    (held), the head's two joints are no arm."""
    stance, model, geometry = _stance("talos_data/robots/talos_reduced.urdf")
    assert stance.soles == ["leg_left_6_link", "leg_right_6_link"]
    assert [len(leg) for leg in stance.legs] == [6, 6] and stance.legs[0][0] == "leg_left_1_joint"
    assert stance.arms == [[f"arm_{side}_{k}_joint" for k in range(1, 8)] for side in ("left", "right")]
    assert stance.posture["leg_left_4_joint"] == 0.859395 and "half_sitting' of talos.srdf" in str(stance.why)
    assert np.ptp(_rise(model, geometry, stance)) < 5e-4  # flat as at the zero posture: taken as it is
    lowest = min(p[:, 2].min() for p in _soles_at(model, geometry, stance, stance.posture).values())
    assert stance.floor == pytest.approx(lowest)  # the floor under them


def test_a_quadruped_carrying_an_arm_stands_on_four_feet_and_moves_its_arm():
    stance, _, _ = _stance("b1_description/urdf/b1-z1.urdf")
    assert stance.soles == ["FL_foot", "FR_foot", "RL_foot", "RR_foot"]
    assert stance.arms == [[f"joint{k}" for k in range(1, 7)]]  # the gripper's joint is held
    assert stance.posture["FL_calf_joint"] == -1.6 and "standing_with_arm_up" in str(stance.why)
    assert stance.room > 0.15  # four feet far apart


def test_a_tilted_srdf_state_is_levelled():
    """iCub's half_sitting tilts its soles by 4.1 mm over their width with the base upright: the legs are
    moved the least that makes them flat."""
    stance, model, geometry = _stance("icub_description/robots/icub.urdf")
    assert "its soles levelled (they were 4.1 mm out of flat)" in stance.why["robot.locked_joints"]
    assert np.ptp(_rise(model, geometry, stance)) < 1e-4


def test_a_humanoid_without_srdf_gets_a_searched_posture_with_bent_knees_and_its_centre_of_mass_over_its_soles():
    stance, model, geometry = _stance("g1_description/urdf/g1_29dof_rev_1_0.urdf")
    assert stance.soles == ["left_ankle_roll_link", "right_ankle_roll_link"]
    assert stance.why["robot.locked_joints"].startswith("searched:")
    soles, zero = _soles_at(model, geometry, stance, stance.posture), _soles_at(model, geometry, stance, {})
    rise = _rise(model, geometry, stance)
    assert np.ptp(rise) < 1e-5  # flat, as at the zero posture
    assert rise.mean() == pytest.approx(KNEE_DROP * abs(zero[stance.soles[0]][:, 2].min()), abs=1e-5)
    assert stance.posture["left_knee_joint"] > 0.2 and stance.posture["right_knee_joint"] > 0.2  # bent
    data = model.createData()
    com = pin.centerOfMass(model, data, _vector(model, stance.posture))
    centre = np.vstack(list(soles.values()))[:, :2].mean(axis=0)
    assert np.linalg.norm(com[:2] - centre) < 1e-5
    assert len(stance.arms) == 2 and all(len(arm) == 7 for arm in stance.arms)


def test_an_arm_stands_on_no_legs_and_a_named_state_must_exist():
    stance, _, _ = _stance("ur_description/urdf/ur3_robot.urdf")
    assert stance is None
    with pytest.raises(ExciteError) as raised:
        _stance("talos_data/robots/talos_reduced.urdf", posture="sitting")
    assert raised.value.describe() == (
        "posture: 'sitting' is not a state the robot's files name; expected half_sitting"
    )


def test_given_soles_need_collision_geometry():
    with pytest.raises(ExciteError, match="soles: 'left_sole_link' has no collision geometry in talos_reduced.urdf"):
        _stance("talos_data/robots/talos_reduced.urdf", soles=["left_sole_link", "right_sole_link"])
