"""The MJCF for MuJoCo: MuJoCo's inverse dynamics of the written file against pinocchio's RNEA of the
URDF (joints welded at their locked values), the effects in MuJoCo's joint fields or listed with
the reason, bodies below MuJoCo's minimum bounded, missing meshes and a missing MuJoCo."""

import sys

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from conftest import CONFIGS, JOINTS, panda_mjcf

from excite_cli.config_file import load_problem
from excite_cli.dynamics.robot import load_robot
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.errors import ExciteError
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term
from excite_cli.identification.reporting.mjcf_out import JOINT_FIELDS, write_mjcf
from excite_cli.identification.reporting.urdf_out import write_urdf

LOCKED = {"panda_joint7": 0.7, "panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}


def _panda(active=JOINTS, locked=None):
    problem = load_problem(CONFIGS / "panda_identify_simulated.yaml", IdentifyProblem)
    problem.robot.active_joints, problem.robot.locked_joints = list(active), dict(locked or {})
    robot = load_robot(problem.robot, problem.folder, joint_rows_only=True, physical=False)
    return problem, robot


def _inverse(path, robot, states, frictionloss=True):
    """MuJoCo's mj_inverse of the file at ``states`` (q, q̇, q̈ arrays), in the robot's joint order."""
    model = mujoco.MjModel.from_xml_path(str(path))
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    if not frictionloss:
        model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS)
    data, dofs = mujoco.MjData(model), [model.joint(n).dofadr[0] for n in robot.joint_names]
    out = []
    for q, qd, qdd in zip(*states):
        data.qpos[dofs], data.qvel[dofs], data.qacc[dofs] = q, qd, qdd  # hinges: qpos and dof indices agree
        mujoco.mj_inverse(model, data)
        out.append(data.qfrc_inverse[dofs].copy())
    return model, np.array(out)


def test_mujoco_gives_pinocchios_torques_with_joints_welded_at_their_locked_values(tmp_path):
    problem, robot = _panda(JOINTS[:6], LOCKED)  # a hinge turned by 0.7 rad, both fingers slid by 2 cm
    urdf, dirs = resolve_urdf(problem.robot, problem.folder)
    written = write_mjcf(urdf, dirs, robot, LOCKED, robot.urdf_parameters(), [], tmp_path / "panda.xml")
    assert any("panda_joint7" in note and "welded" in note for note in written.notes)
    states = robot.random_states(50, np.random.default_rng(1))
    model, tau = _inverse(written.path, robot, states)
    assert model.nv == 6 and model.neq == 0  # the mimic constraint of the welded finger is gone
    truth = np.array([robot.torques(*x) for x in zip(*states)])
    assert np.abs(tau - truth).max() <= 1e-5 * np.abs(truth).max()
    # MuJoCo fuses the welded links into link 6: their boxes (a fingertip pad each, 18.5 mm off the
    # finger's axis in its frame) are where pinocchio's full URDF model puts them at the locked values
    full = pin.buildModelFromUrdf(str(urdf))
    q_full, pin_data, data = pin.neutral(full), full.createData(), mujoco.MjData(model)
    for name, value in LOCKED.items():
        q_full[full.idx_qs[full.getJointId(name)]] = value
    pads = np.flatnonzero(np.all(np.isclose(model.geom_size, [0.011, 0.0075, 0.01]), axis=1))
    assert pads.size == 2
    for q in states[0][:5]:
        q_full[[full.idx_qs[full.getJointId(n)] for n in robot.joint_names]] = q
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        pin.framesForwardKinematics(full, pin_data, q_full)
        expected = [
            pin_data.oMf[full.getFrameId(f"panda_{side}finger")] * np.array([0.0, sign * 0.0185, 0.011])
            for side, sign in (("left", 1), ("right", -1))
        ]
        found = data.geom_xpos[pads]
        distances = np.linalg.norm(found[:, None, :] - np.array(expected)[None, :, :], axis=2)
        assert distances.min(axis=0).max() < 1e-5  # 6-digit numbers in the file


def test_effects_go_to_mujocos_joint_fields_or_are_listed_with_the_reason(tmp_path):
    problem, robot = _panda()
    urdf, dirs = resolve_urdf(problem.robot, problem.folder)
    coupled = Term("armature", 4, coupling=(0, 0, 0, 0, 1.0, 1.0, 0))
    effects = [
        (Term("armature", 3), "Ia", 0.2),
        (Term("viscous", 0), "Fv", 0.3),
        (Term("coulomb", 1), "Fc", 0.4),
        (Term("coulomb", 2), "Fc", -0.1),
        (Term("offset", 2), "tau0", 0.5),
        (coupled, "Ia", 0.01),
    ]
    written = write_mjcf(urdf, dirs, robot, {}, robot.urdf_parameters(), effects, tmp_path / "panda.xml")
    model = mujoco.MjModel.from_xml_path(str(written.path))
    dof = {name: model.joint(name).dofadr[0] for name in JOINTS}
    assert model.dof_armature[dof["panda_joint4"]] == pytest.approx(0.2)
    assert model.dof_damping[dof["panda_joint1"]] == pytest.approx(0.3)
    assert model.dof_frictionloss[dof["panda_joint2"]] == pytest.approx(0.4)
    assert model.dof_frictionloss[dof["panda_joint3"]] == 0.0  # negative: not written
    assert model.dof_damping[dof["panda_joint2"]] == 0.0  # no URDF <dynamics damping> left anywhere
    assert set(JOINT_FIELDS.values()) >= {a for _, a in written.fields}
    # one torque motor per joint, limited to the URDF's effort (87 Nm, 12 Nm from joint 5 on)
    assert [model.actuator(k).name for k in range(model.nu)] == JOINTS
    np.testing.assert_array_equal(model.actuator_ctrlrange[:, 1], [87.0] * 4 + [12.0] * 3)
    reasons = {t.effect + ("*" if t.coupling else ""): why for t, _, _, why in written.unwritten}
    assert reasons == {
        "coulomb": "negative, MuJoCo's frictionloss cannot be",
        "offset": "no MuJoCo joint field",
        "armature*": "a motor turning with several joints",
    }
    # viscous friction acts as MuJoCo damping, armature on q̈: excite's terms exactly
    states = robot.random_states(10, np.random.default_rng(2))
    _, tau = _inverse(written.path, robot, states, frictionloss=False)
    rigid = np.array([robot.torques(*x) for x in zip(*states)])
    q, qd, qdd = states
    np.testing.assert_allclose(tau[:, 3] - rigid[:, 3], 0.2 * qdd[:, 3], atol=1e-5 * np.abs(rigid).max())
    np.testing.assert_allclose(tau[:, 0] - rigid[:, 0], 0.3 * qd[:, 0], atol=1e-5 * np.abs(rigid).max())
    # the motors play those torques: forward dynamics gives back q̈ (friction loss and limits off)
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS) | int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_CLAMPCTRL)
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:], data.ctrl[:] = q[0], qd[0], tau[0]
    mujoco.mj_forward(model, data)
    np.testing.assert_allclose(data.qacc, qdd[0], rtol=1e-6, atol=1e-6)


def test_a_body_below_mujocos_smallest_mass_is_bounded_and_missing_meshes_are_left_out(tmp_path):
    problem, robot = _panda()
    urdf, _ = resolve_urdf(problem.robot, problem.folder)
    standard = robot.urdf_parameters().copy()
    standard[-10:] = 0.0  # link 7 (hand and fingers merged in) not excited: nothing identified
    written = write_mjcf(urdf, [], robot, {}, standard, [], tmp_path / "panda.xml")  # no package folder
    model = mujoco.MjModel.from_xml_path(str(written.path))
    assert model.nmesh == 0 and any("left out (not found)" in note for note in written.notes)
    assert any(note.startswith("panda_link7: mass or inertia below") for note in written.notes)
    assert model.body("panda_link7").mass[0] == pytest.approx(1e-6)


def test_without_mujoco_the_option_says_so_in_one_line(tmp_path, monkeypatch):
    problem, robot = _panda()
    urdf, dirs = resolve_urdf(problem.robot, problem.folder)
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco raises ImportError
    with pytest.raises(ExciteError, match="needs MuJoCo, which is not installed") as error:
        write_mjcf(urdf, dirs, robot, {}, robot.urdf_parameters(), [], tmp_path / "panda.xml")
    assert error.value.field == "mjcf_out" and not (tmp_path / "panda.xml").exists()


def test_an_mjcf_robot_is_written_from_its_mjcf_and_its_controls_left_out(tmp_path):
    """A robot described in MJCF (MuJoCo wrote the Panda's, then a lab's position actuators and a
    keyframe were added): the identified MJCF is built from that file; its actuators give way to torque
    motors and its keyframe (of a state with the fingers' joints) is left out, said in the notes."""
    path = panda_mjcf(tmp_path)
    spec = mujoco.MjSpec.from_file(str(path))
    for name in JOINTS:
        spec.add_actuator(name=f"servo_{name}", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    spec.add_key(name="home", qpos=np.zeros(9))
    path.write_text(spec.to_xml())
    problem, _ = _panda()
    problem.robot.urdf, problem.robot.source = str(path), "file"
    robot = load_robot(problem.robot, None, joint_rows_only=True, physical=False)
    written = write_mjcf(path, [], robot, {}, robot.urdf_parameters(), [], tmp_path / "identified.xml")
    assert "the file's actuators left out (7)" in written.notes and "the file's keyframes left out (1)" in written.notes
    states = robot.random_states(20, np.random.default_rng(2))
    model, tau = _inverse(written.path, robot, states)
    assert model.nu == 7 and [model.actuator(k).name for k in range(7)] == JOINTS  # the motors excite writes
    truth = np.array([robot.torques(*x) for x in zip(*states)])
    assert np.abs(tau - truth).max() <= 1e-5 * np.abs(truth).max()
    with pytest.raises(ExciteError, match="urdf_out: the robot's file panda.xml is an MJCF"):
        write_urdf(path, tmp_path / "identified.urdf", robot, robot.urdf_parameters(), [], "note")
