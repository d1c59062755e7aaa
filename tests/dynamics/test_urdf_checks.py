"""A robot that can be: bodies and joints a model cannot have are refused by name, before pinocchio."""

import warnings

import pytest
from conftest import GOOD, PENDULUM

from excite_cli.dynamics.urdf_checks import MAX_LINKS, check_urdf
from excite_cli.errors import ExciteError, ExciteWarning


def _urdf(tmp_path, **fields):
    path = tmp_path / "robot.urdf"
    path.write_text(PENDULUM.format(**{**GOOD, "mimic": "", **fields}))
    return path


def test_the_pendulum_is_a_robot_that_can_be(tmp_path):
    check_urdf(_urdf(tmp_path), ["hinge"])


@pytest.mark.parametrize(
    "fields, active, expected",
    [
        ({"mass": "-1.5"}, ["hinge"], "arm"),  # a negative mass
        ({"mass": "nan"}, ["hinge"], "arm"),  # not a number
        ({"izz": "0.5"}, ["hinge"], "arm"),  # principal moments breaking the triangle inequality
        ({"lower": "3.0"}, ["hinge"], "hinge"),  # lower limit above the upper one
        ({"tip_ixx": "1.0"}, ["hinge"], "tip"),  # the tip moves with the hinge: its inertia too
    ],
)
def test_a_body_or_joint_that_cannot_be_is_named(tmp_path, fields, active, expected):
    with pytest.raises(ExciteError, match=expected):
        check_urdf(_urdf(tmp_path, **fields), active)


LOOP = '<joint name="loop" type="revolute"><parent link="tip"/><child link="arm"/><axis xyz="0 1 0"/></joint>'


def test_a_closed_kinematic_chain_is_named_not_misread(tmp_path):
    """pinocchio reads a link with two parent joints as 'no body named tip', far from the cause."""
    path = _urdf(tmp_path)
    path.write_text(path.read_text().replace("</robot>", LOOP + "</robot>"))
    with pytest.raises(ExciteError, match=r"link 'arm' is the child of 2 joints \('hinge', 'loop'\)"):
        check_urdf(path, ["hinge"])


def test_joints_that_form_a_ring_have_no_root(tmp_path):
    path = _urdf(tmp_path)
    ring = '<joint name="ring" type="fixed"><parent link="tip"/><child link="base"/></joint>'
    path.write_text(path.read_text().replace("</robot>", ring + "</robot>"))
    with pytest.raises(ExciteError, match="joints 'ring', 'hinge', 'tip_joint' form a closed kinematic chain"):
        check_urdf(path, ["hinge"])


def test_a_ring_of_joints_beside_the_tree_is_named(tmp_path):
    """Two links joined both ways, apart from the pendulum: pinocchio leaves them out, and the ring's
    joints were then reported as 'not a joint of the robot'."""
    path = _urdf(tmp_path)
    ring = (
        '<link name="a"/><link name="b"/>'
        '<joint name="ab" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>'
        '<joint name="ba" type="revolute"><parent link="b"/><child link="a"/><axis xyz="0 0 1"/></joint>'
    )
    path.write_text(path.read_text().replace("</robot>", ring + "</robot>"))
    with pytest.raises(
        ExciteError, match="joints 'ba', 'ab' form a closed kinematic chain apart from the root link 'base'"
    ):
        check_urdf(path, ["hinge"])


def test_a_urdf_beyond_the_size_pinocchio_holds_is_refused_before_it(tmp_path):
    """pinocchio's parser crashes (exit 139, no output) on a chain of 4 000 links."""
    links = "".join(f'<link name="l{k}"/>' for k in range(MAX_LINKS + 1))
    joints = "".join(
        f'<joint name="j{k}" type="fixed"><parent link="l{k - 1}"/><child link="l{k}"/></joint>'
        for k in range(1, MAX_LINKS + 1)
    )
    path = tmp_path / "chain.urdf"
    path.write_text(f'<robot name="chain">{links}{joints}</robot>')
    with pytest.raises(ExciteError, match=f"the URDF has {MAX_LINKS + 1} links; expected at most {MAX_LINKS}"):
        check_urdf(path, [])


MIMIC = '<mimic joint="hinge" multiplier="2"/>'


def test_a_mimic_joint_held_while_its_leader_moves_is_refused_unless_locked_on_purpose(tmp_path):
    path = _urdf(tmp_path, mimic=MIMIC)
    with pytest.raises(ExciteError, match="'tip_joint' mimics active joint 'hinge' \\(multiplier 2") as caught:
        check_urdf(path, ["hinge"])
    assert caught.value.field == "robot.locked_joints"
    check_urdf(path, ["hinge"], locked=["tip_joint"])  # held on purpose
    with pytest.raises(ExciteError, match="a coupling the model does not represent"):
        check_urdf(path, ["hinge", "tip_joint"])  # the follower itself may not be active


@pytest.mark.parametrize(
    "name, text, expected",
    [
        (
            "arm.urdf.xacro",
            '<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:include filename="x.xacro"/></robot>',
            "arm.urdf.xacro is a xacro file: its macros are not expanded; expected the URDF it expands to: "
            "xacro arm.urdf.xacro > robot.urdf",
        ),
        (
            "arm.urdf",  # a vendor's xacro saved under a URDF name: its macros give it away
            '<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:arm prefix=""/></robot>',
            "arm.urdf is a xacro file",
        ),
        ("scene.sdf", '<sdf version="1.6"><model name="m"/></sdf>', "its root element is <sdf>, not <robot>"),
    ],
)
def test_a_file_that_is_no_urdf_says_what_it_is_and_the_next_step(tmp_path, name, text, expected):
    (tmp_path / name).write_text(text)
    with pytest.raises(ExciteError) as raised:
        check_urdf(tmp_path / name, [])
    assert expected in raised.value.describe()


def test_a_joint_that_moves_no_mass_is_a_warning(tmp_path):
    """A URDF without inertias (ROS-Industrial's iiwa): the torques export would write are all 0."""
    massless = PENDULUM.format(**{**GOOD, "mimic": "", "mass": "0", "tip_mass": "0"})
    (tmp_path / "robot.urdf").write_text(massless)
    with pytest.warns(ExciteWarning, match="robot.urdf gives no mass to anything hinge move"):
        check_urdf(tmp_path / "robot.urdf", ["hinge"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_urdf(_urdf(tmp_path), ["hinge"])  # a massless frame beside bodies with mass is no warning
