"""The postures an SRDF names, and which SRDF belongs to a URDF: read against example-robot-data's files
(their group states as written) and files made here."""

import pytest

from excite_cli.dynamics.robot_files import example_robot_data_root, open_source
from excite_cli.dynamics.srdf import srdf_beside, srdf_states
from excite_cli.errors import ExciteError

ROBOTS = example_robot_data_root() / "example-robot-data" / "robots"
SRDF = """<?xml version="1.0"?>
<robot name="{name}">
  <group_state name="half_sitting" group="all">
    <joint name="root_joint" value="0. 0. 0.6 0. 0. 0. 1."/>
    <joint name="knee" value="{knee}"/>
  </group_state>
  <group_state name="standing_tall" group="all"><joint name="knee" value="0"/></group_state>
</robot>
"""


def test_group_states_are_read_one_value_per_joint_and_the_root_pose_left_out(tmp_path):
    path = tmp_path / "walker.srdf"
    path.write_text(SRDF.format(name="walker", knee="0.52"))
    assert srdf_states(path) == {"half_sitting": {"knee": 0.52}, "standing_tall": {"knee": 0.0}}


def test_a_value_that_is_not_a_number_is_named(tmp_path):
    path = tmp_path / "walker.srdf"
    path.write_text(SRDF.format(name="walker", knee="bent"))
    with pytest.raises(ExciteError) as raised:
        srdf_states(path)
    assert raised.value.describe() == (
        "srdf: walker.srdf: state 'half_sitting' gives joint 'knee' the value 'bent'; expected a number [rad or m]"
    )
    path.write_text("<mujoco/>")
    with pytest.raises(ExciteError, match="srdf: walker.srdf is not an SRDF"):
        srdf_states(path)


def test_the_srdf_beside_a_urdf_is_found_by_its_name_or_its_robot(tmp_path):
    """example-robot-data: b1-z1.urdf has b1-z1.srdf (b1.srdf names the same robot); talos_reduced.urdf has
    talos.srdf, the one SRDF of robot 'talos'; the G1 has none."""
    assert srdf_beside(ROBOTS / "b1_description/urdf/b1-z1.urdf").name == "b1-z1.srdf"
    assert srdf_beside(ROBOTS / "talos_data/robots/talos_reduced.urdf").name == "talos.srdf"
    assert srdf_beside(ROBOTS / "g1_description/urdf/g1_29dof_rev_1_0.urdf") is None
    (tmp_path / "urdf").mkdir()
    (tmp_path / "srdf").mkdir()
    urdf = tmp_path / "urdf" / "walker_v2.urdf"
    urdf.write_text('<robot name="walker"><link name="base"/></robot>')
    for stem in ("a", "b"):  # two SRDFs of the robot, neither of the URDF's name: none is guessed
        (tmp_path / "srdf" / f"{stem}.srdf").write_text(SRDF.format(name="walker", knee="0.5"))
    assert srdf_beside(urdf) is None
    (tmp_path / "srdf" / "walker.srdf").write_text(SRDF.format(name="walker", knee="0.5"))
    assert srdf_beside(urdf).name == "walker.srdf"  # the one whose name the URDF's begins with


def test_a_urdf_source_names_its_srdf_states_as_written():
    talos = open_source(ROBOTS / "talos_data/robots/talos_reduced.urdf")
    states = talos.named_states()
    assert talos.states_file.name == "talos.srdf" and list(states) == ["half_sitting"]
    assert states["half_sitting"]["leg_left_4_joint"] == 0.859395  # the knee, as the file writes it
