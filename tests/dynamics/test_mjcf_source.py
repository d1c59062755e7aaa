"""An MJCF read as MuJoCo compiles it is the same robot as its URDF: MuJoCo writes the Panda's
MJCF from example-robot-data's URDF, and excite's regressor and base parameters of it equal those of
the URDF. MuJoCo's units (degrees unless said), joints without a range, couplings, and what the
parser would drop are each checked."""

import numpy as np
import pytest
from conftest import JOINTS, included_arm_mjcf, panda_mjcf

from excite_cli.config import RobotConfig
from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.mjcf_compiled import is_mjcf
from excite_cli.dynamics.mjcf_equalities import mjcf_couplings
from excite_cli.dynamics.robot import load_robot
from excite_cli.dynamics.robot_files import open_source
from excite_cli.errors import ExciteError, ExciteWarning

ARM = """<mujoco model="arm">{compiler}
  <worldbody>
    <body name="upper" pos="0 0 0.1">
      <inertial pos="0 0 0.1" mass="1" diaginertia="0.01 0.01 0.001"/>
      <joint name="shoulder" axis="0 1 0" range="-90 90"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.03"/>
      <body name="fore" pos="0 0 0.2">
        <joint name="elbow" axis="0 1 0" {elbow}/>
        <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.03"/>
        <body name="finger" pos="0 0 0.2">
          <joint name="finger" axis="0 1 0" range="0 30"/>
          <geom type="box" size="0.01 0.01 0.01"/>
        </body>
      </body>
    </body>
  </worldbody>{equality}
</mujoco>
"""


def arm(tmp_path, compiler="", elbow='range="-120 120"', equality=""):
    path = tmp_path / "arm.xml"
    path.write_text(ARM.format(compiler=compiler, elbow=elbow, equality=equality))
    return path


def test_the_mjcf_panda_has_the_regressor_and_base_parameters_of_its_urdf(tmp_path):
    path = panda_mjcf(tmp_path)
    assert is_mjcf(path) and mjcf_couplings(path) == {
        "panda_finger_joint2": ("panda_finger_joint1", "polycoef 0 1 0 0 0")
    }
    locked = {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}
    mjcf = load_robot(RobotConfig(urdf=str(path), active_joints=JOINTS, locked_joints=locked), collision=True)
    urdf = load_robot(
        RobotConfig(
            urdf="panda_description/urdf/panda.urdf",
            source="example-robot-data",
            active_joints=JOINTS,
            locked_joints=locked,
        )
    )
    np.testing.assert_allclose(mjcf.lower, urdf.lower) and np.testing.assert_allclose(mjcf.upper, urdf.upper)
    assert np.all(np.isinf(mjcf.velocity_limit))  # MJCF has none: limits.velocity asks
    rng = np.random.default_rng(0)
    for q, qd, qdd in zip(*(rng.uniform(-1, 1, (3, 5, 7)))):
        scale = np.abs(urdf.regressor(q, qd, qdd)).max()
        assert np.abs(mjcf.regressor(q, qd, qdd) - urdf.regressor(q, qd, qdd)).max() < 1e-6 * scale
    base_mjcf, base_urdf = compute_base_parameters(mjcf), compute_base_parameters(urdf)
    assert base_mjcf.names == base_urdf.names and base_mjcf.count == 43
    values = base_mjcf.from_standard(mjcf.urdf_parameters()), base_urdf.from_standard(urdf.urdf_parameters())
    assert np.abs(values[0] - values[1]).max() < 1e-5 * np.abs(values[1]).max()  # MuJoCo writes 6 digits
    assert mjcf.collision_model.ngeoms >= 8  # its geoms: a mesh per link


def test_angles_are_read_in_mujocos_unit_and_a_joint_without_range_gets_one(tmp_path):
    robot = load_robot(RobotConfig(urdf=str(arm(tmp_path)), active_joints=["shoulder", "elbow"]))
    np.testing.assert_allclose(robot.lower, np.radians([-90, -120])) and np.testing.assert_allclose(
        robot.upper, np.radians([90, 120])
    )
    radian = arm(tmp_path, compiler='<compiler angle="radian"/>', elbow="")
    robot = load_robot(
        RobotConfig(urdf=str(radian), active_joints=["shoulder", "elbow"], joint_ranges={"elbow": (-1.0, 2.0)})
    )
    np.testing.assert_allclose(robot.lower, [-90, -1.0]) and np.testing.assert_allclose(robot.upper, [90, 2.0])
    with pytest.raises(ExciteError, match=r"robot.joint_ranges.shoulder: \[-100, 0\] reaches past the limits"):
        load_robot(RobotConfig(urdf=str(radian), active_joints=["shoulder"], joint_ranges={"shoulder": (-100.0, 0.0)}))


def test_a_coupled_joint_is_checked_as_a_mimic(tmp_path):
    equality = '<equality><joint joint1="finger" joint2="elbow"/></equality>'
    path = arm(tmp_path, equality=equality)
    with pytest.raises(ExciteError, match="robot.locked_joints: joint 'finger' mimics active joint 'elbow'"):
        load_robot(RobotConfig(urdf=str(path), active_joints=["shoulder", "elbow"]))
    with pytest.raises(ExciteError, match="robot.active_joints: joint 'finger' mimics 'elbow'"):
        load_robot(RobotConfig(urdf=str(path), active_joints=["finger"]))
    held = RobotConfig(urdf=str(path), active_joints=["shoulder", "elbow"], locked_joints={"finger": 0.0})
    assert load_robot(held).joint_names == ["shoulder", "elbow"]


def test_a_tendon_coupling_is_checked_as_a_mimic_and_a_closed_chain_keeps_its_joints_still(tmp_path):
    """Issue 102: a fixed tendon's equality and a connect were ignored (the same chain as a URDF is
    refused): now the tendon's joints are a coupling and the chain's joints may not be active."""
    tendon = (
        '<tendon><fixed name="pair"><joint joint="elbow" coef="1"/><joint joint="finger" coef="-1"/></fixed></tendon>'
        '<equality><tendon tendon1="pair"/></equality>'
    )
    path = arm(tmp_path, equality=tendon)
    assert mjcf_couplings(path) == {"finger": ("elbow", "tendon equality of 'pair'")}
    with pytest.raises(ExciteError, match="robot.locked_joints: joint 'finger' mimics active joint 'elbow'"):
        load_robot(RobotConfig(urdf=str(path), active_joints=["shoulder", "elbow"]))
    held = RobotConfig(urdf=str(path), active_joints=["shoulder", "elbow"], locked_joints={"finger": 0.0})
    assert load_robot(held).joint_names == ["shoulder", "elbow"]
    chain = '<equality><connect body1="finger" body2="upper" anchor="0 0 0"/></equality>'
    path = arm(tmp_path, equality=chain)
    with pytest.raises(ExciteError) as refused:
        load_robot(RobotConfig(urdf=str(path), active_joints=["shoulder", "elbow"]))
    assert refused.value.describe().startswith(
        "robot.active_joints: joint 'elbow' is in a closed kinematic chain (<equality><connect> of bodies "
        "'finger' and 'upper', through 'elbow', 'finger')"
    )
    assert load_robot(RobotConfig(urdf=str(path), active_joints=["shoulder"])).joint_names == ["shoulder"]
    welded = arm(tmp_path, equality='<equality><weld body1="fore"/></equality>')  # to the world: shoulder, elbow
    with pytest.raises(ExciteError, match="joint 'shoulder' is in a closed kinematic chain"):
        load_robot(RobotConfig(urdf=str(welded), active_joints=["shoulder"]))


def test_a_ball_joint_held_is_said_and_cannot_be_held_by_one_value(tmp_path):
    """Issue 102: an MJCF ball joint was held at its reference without a word."""
    path = tmp_path / "arm.xml"
    path.write_text(ARM.format(compiler="", elbow='type="ball"', equality="").replace('axis="0 1 0" type', "type"))
    with pytest.warns(
        ExciteWarning, match="robot.active_joints: 'elbow' is a joint of more than one degree of freedom"
    ):
        assert load_robot(RobotConfig(urdf=str(path), active_joints=["shoulder", "finger"])).joint_names == [
            "shoulder",
            "finger",
        ]
    with pytest.raises(ExciteError, match="robot.locked_joints.elbow: 'elbow' has 3 degrees of freedom"):
        load_robot(RobotConfig(urdf=str(path), active_joints=["shoulder"], locked_joints={"elbow": 0.1}))
    with pytest.raises(ExciteError, match="robot.active_joints: 'elbow' is not a 1-DoF"):
        load_robot(RobotConfig(urdf=str(path), active_joints=["elbow"]))


def test_bodies_in_frames_are_read_as_mujoco_reads_them(tmp_path):
    """MuJoCo writes a URDF's fixed links as <frame> elements (pinocchio's parser skipped them with
    what is in them: the Panda's fingers and hand vanished, mass and all): the same model as without."""
    plain = load_robot(RobotConfig(urdf=str(panda_mjcf(tmp_path)), active_joints=JOINTS))
    (tmp_path / "framed").mkdir()
    framed_path = panda_mjcf(tmp_path / "framed", frames=True)
    framed = load_robot(RobotConfig(urdf=str(framed_path), active_joints=JOINTS))
    assert framed.model.njoints == plain.model.njoints
    values = plain.urdf_parameters()  # MuJoCo writes the framed file to 6 digits
    np.testing.assert_allclose(framed.urdf_parameters(), values, atol=1e-5 * np.abs(values).max())


def test_an_mjcf_with_includes_frames_a_floor_and_actuators_is_the_robot_mujoco_simulates(tmp_path):
    """What MuJoCo compiles, excite models: every joint (one in an included file, one in a <frame>),
    the floor left to the world, torque limits from the actuators (gear × ctrlrange of a motor, the
    forcerange, a general actuator's gain; a position servo's ctrlrange is a position), the damping
    and frictionloss said; MuJoCo's own inverse dynamics of the file equals excite's (RNEA with the
    armature) once the said damping is added, at random states, constraints off."""
    mujoco = pytest.importorskip("mujoco")
    included_arm_mjcf(tmp_path)
    joints = ["joint1", "joint2", "joint3"]
    with pytest.warns(
        ExciteWarning,
        match=r"damping \[N·m·s/rad\] \(joint1 0.1, joint2 0.5, joint3 0.1\).*"
        r"frictionloss \[N·m\] \(joint2 0.2\)",
    ):
        robot = load_robot(RobotConfig(urdf=str(tmp_path / "arm.xml"), active_joints=joints), collision=True)
    assert robot.joint_names == joints
    np.testing.assert_allclose(robot.model.effortLimit[robot.v_idx], [50.0, 40.0, 20.0])
    np.testing.assert_allclose(robot.lower, np.radians([-170, -90, -90]))
    assert len(robot.collision_model.geometryObjects) == 3  # not the floor
    mj = mujoco.MjModel.from_xml_path(str(tmp_path / "arm.xml"))
    mj.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    data = mujoco.MjData(mj)
    rng = np.random.default_rng(0)
    for q, qd, qdd in zip(*rng.uniform(-1, 1, (3, 5, 3))):
        data.qpos[:], data.qvel[:], data.qacc[:] = q, qd, qdd
        mujoco.mj_inverse(mj, data)
        excite = robot.torques(q, qd, qdd) + mj.dof_damping * qd
        np.testing.assert_allclose(excite, data.qfrc_inverse, rtol=1e-9, atol=1e-9)
    included_arm_mjcf(tmp_path, "hand.xml", "missing.xml")
    with pytest.raises(ExciteError, match=r"robot.urdf: MuJoCo cannot compile missing.xml: .*'hand.xml'"):
        load_robot(RobotConfig(urdf=str(tmp_path / "missing.xml"), active_joints=joints))


ON_A_FLOOR = """<mujoco model="arm"><compiler angle="radian"/><worldbody>
  <geom name="floor" type="plane" size="2 2 0.1"/>
  <body name="link1" pos="0 0 0.1"><joint name="j1" type="hinge" axis="0 0 1" range="-2 2"/>
    <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/></body>
</worldbody></mujoco>"""


def test_a_floor_in_the_worldbody_is_the_world_s(tmp_path):
    """A floor geom directly in <worldbody> ended init in an IndexError."""
    (tmp_path / "arm.xml").write_text(ON_A_FLOOR)
    robot = load_robot(RobotConfig(urdf=str(tmp_path / "arm.xml"), active_joints=["j1"]), collision=True)
    assert [robot.model.frames[o.parentFrame].name for o in robot.collision_model.geometryObjects] == ["link1"]


FLOATING = """<mujoco model="walker">
  <asset><mesh name="shell" file="absent/shell.stl"/></asset>
  <worldbody>
    <body name="pelvis" pos="0 0 0.5">
      <freejoint name="floating_base_joint"/>
      <inertial pos="0 0 0" mass="5" diaginertia="0.05 0.05 0.05"/>
      <geom type="mesh" mesh="shell"/>
      <body name="leg" pos="0 0 -0.1">
        <joint name="hip" axis="0 1 0" range="-1 1"/>
        <inertial pos="0 0 -0.2" mass="1" diaginertia="0.01 0.01 0.001"/>
        <geom type="sphere" pos="0 0 -0.4" size="0.01"/>
      </body>
    </body>{loose}
  </worldbody>
  <keyframe><key name="crouch" qpos="0 0 0.45 1 0 0 0 0.3"/></keyframe>
</mujoco>
"""
LOOSE = """
    <body name="box" pos="1 0 0.1"><freejoint/><inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/></body>"""


def test_a_free_root_its_keyframes_and_no_mesh_read_for_the_model(tmp_path):
    """The free joint is named, a keyframe is a named posture (the free joint's pose left out), and the model
    (floating or not) compiles without the absent mesh: the bodies' inertias are given, so no mesh changes
    them (the collision geometry still needs it, and says so)."""
    path = tmp_path / "walker.xml"
    path.write_text(FLOATING.format(loose=""))
    source = open_source(path)
    assert source.kind == "MJCF" and source.free_root() == "floating_base_joint"
    assert source.named_states() == {"crouch": {"hip": pytest.approx(0.3)}}
    floating = source.model(floating=True)
    assert floating.names[1] == "root_joint" and floating.nq == 8 and source.model().nq == 1
    with pytest.raises(ExciteError, match="robot.urdf: MuJoCo cannot compile walker.xml"):
        source.geometry(floating)


def test_a_second_free_body_is_one_line_not_a_traceback(tmp_path):
    path = tmp_path / "walker.xml"
    path.write_text(FLOATING.format(loose=LOOSE))
    with pytest.raises(ExciteError) as raised:
        open_source(path).model(floating=True)
    assert raised.value.describe().startswith(
        "robot.floating_base: body 'box' has a free joint of its own: the file holds more than one free body"
    )


def test_a_body_whose_inertia_comes_from_its_mesh_needs_the_mesh(tmp_path):
    """Without <inertial>, MuJoCo takes a body's inertia from its geoms: without the mesh it would change,
    so the mesh is read (and its absence named)."""
    path = tmp_path / "walker.xml"
    path.write_text(
        FLOATING.format(loose="").replace('<inertial pos="0 0 0" mass="5" diaginertia="0.05 0.05 0.05"/>', "")
    )
    with pytest.raises(ExciteError, match="MuJoCo cannot compile walker.xml"):
        open_source(path).model()
