"""The robot MuJoCo compiles for a rehearsal: a standing robot on a free root with its soles as its only
contacts and a floor under them, its held joints driven by their PD (or welded); a fixed-base arm with its
collision geometry, the config's world shapes and the self-collision pairs the config excludes; a lab MJCF
that lacks a joint of the problem, and a machine without MuJoCo, refused in one line."""

import sys

import pytest
from conftest import CONFIGS, panda_mjcf

from excite_cli.config.rehearsal import RehearsalConfig
from excite_cli.config_file import load_problem
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.errors import ExciteError
from excite_cli.rehearsal.mujoco_robot import rehearsal_robot, require_mujoco


def compiled(name: str, welded: bool = False, urdf=None):
    problem = load_problem(CONFIGS / name)
    found, folders = resolve_urdf(problem.robot, problem.folder)
    return problem, rehearsal_robot(
        problem.robot, problem.constraints, urdf or found, folders, RehearsalConfig(), None, welded
    )


def test_a_standing_robot_has_a_free_root_its_soles_and_a_floor_under_them():
    import mujoco

    problem, robot = compiled("g1_arms.yaml")
    model = robot.model
    assert robot.standing and model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    assert len(robot.held) == 15 and set(robot.held).isdisjoint(problem.robot.active_joints)  # legs and waist
    assert model.nu == 14 + 15 and model.nv == 6 + 14 + 15
    bodies = {model.body(int(model.geom_bodyid[g])).name for g in range(model.ngeom)}
    assert bodies == {"world", *problem.constraints.zmp.support_links}  # the soles' spheres and the floor
    data = mujoco.MjData(model)
    model_floor = model.geom("floor").pos[2]
    mujoco.mj_forward(model, data)  # qpos0: every joint at 0, the G1's locked posture
    spheres = [g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE]
    assert min(data.geom_xpos[g, 2] - model.geom_size[g, 0] for g in spheres) == pytest.approx(model_floor, abs=1e-9)


def test_welded_held_joints_leave_the_arms_on_a_free_root():
    _, robot = compiled("g1_arms.yaml", welded=True)
    assert not robot.held and robot.model.nv == 6 + 14 and robot.model.nu == 14


def test_a_fixed_base_arm_keeps_its_collision_geometry_and_the_config_s_world():
    problem, robot = compiled("panda.yaml")
    model = robot.model
    assert not robot.standing and model.nv == 7 and model.geom("table").size[0] > 0
    assert sum(model.geom_bodyid[g] > 0 for g in range(model.ngeom)) >= 8  # the links' collision meshes
    assert any("panda_link5-panda_link7" in note and "self_collision" in note for note in robot.notes)


def test_a_lab_mjcf_without_a_joint_of_the_problem_is_refused_naming_it(tmp_path):
    mjcf = panda_mjcf(tmp_path)
    mjcf.write_text(mjcf.read_text().replace('name="panda_joint4"', 'name="elbow"'))
    with pytest.raises(ExciteError, match="has no joint panda_joint4"):
        compiled("panda.yaml", urdf=mjcf)


def test_without_mujoco_the_rehearsal_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(ExciteError, match=r"pip install 'excite\[mujoco\]'"):
        require_mujoco()
