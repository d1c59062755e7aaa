"""Robots as labs describe them, through the commands a user types: an MJCF made by MuJoCo from
example-robot-data's Panda goes init → check → optimize → identify and identifies the base parameters
its URDF does on the same runs; continuous joints get a range in the drafted config; init without
collision geometry; a robot with no home posture still gets its config, with what binds commented."""

from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml
from conftest import CHAIN_INERTIAL, GOOD, PENDULUM, assert_refused, chain_urdf, included_arm_mjcf, panda_mjcf
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.drafting.joints import CONTINUOUS_RANGE

DATA = Path(__file__).resolve().parents[2] / "data" / "panda_simulated"
runner = CliRunner()
#: A mesh: a tetrahedron of 10 cm, as ASCII STL.
FACES = [("0 0 0", "0.1 0 0", "0 0.1 0"), ("0 0 0", "0 0.1 0", "0 0 0.1"), ("0 0 0", "0 0 0.1", "0.1 0 0")]
FACES.append(("0.1 0 0", "0 0.1 0", "0 0 0.1"))
TETRAHEDRON = (
    "solid t\n"
    + "".join(
        "facet normal 0 0 0\nouter loop\n" + "".join(f"vertex {v}\n" for v in face) + "endloop\nendfacet\n"
        for face in FACES
    )
    + "endsolid t\n"
)


def _ok(argv: list[str]) -> str:
    result = runner.invoke(app, argv, env={"COLUMNS": "300"})
    assert result.exit_code == 0, result.output
    return result.output


def _small(path, **optimizer) -> None:
    """The config at ``path`` with a short trajectory and one short restart (a test's budget)."""
    config = yaml.safe_load(path.read_text())
    config["trajectory"].update(harmonics=3, cost_samples=25, cost_period=0.4)
    config["optimizer"] = {"max_iterations": 10, "restarts": 1, "workers": 1, **optimizer}
    path.write_text(yaml.safe_dump(config))


@pytest.mark.end_to_end
def test_an_mjcf_arm_goes_init_check_optimize_identify_with_the_base_parameters_of_its_urdf(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    panda_mjcf(tmp_path)
    said = _ok(["init", "panda.xml"])
    assert "held as a gripper's, a hand's or a mobile base's: panda_finger_joint1, panda_finger_joint2" in said
    assert "1 rad/s where it has none" in said  # MJCF has no velocity limits
    _small(tmp_path / "panda.yaml")
    assert "optimize would start" in _ok(["check", "panda.yaml"])
    _ok(["optimize", "panda.yaml", "--iterations", "1", "--output", "panda.h5"])
    with h5py.File("panda.h5") as f:
        assert len(f["iterations"]) == 1
    runs = ["--runs", str(DATA / "run_1.csv"), "--runs", str(DATA / "run_2.csv")]
    estimates = []
    for name, robot in (("mjcf", "panda.xml"), ("urdf", "panda_description/urdf/panda.urdf")):
        _ok(["init", robot, "--kind", "identify", *runs, "--output", f"{name}.yaml"])
        config = yaml.safe_load((tmp_path / f"{name}.yaml").read_text())
        config["identification"]["candidates"] = ["coulomb", "viscous"]  # the runs' effects: a short search
        (tmp_path / f"{name}.yaml").write_text(yaml.safe_dump(config))
        _ok(["identify", f"{name}.yaml", "--output", f"{name}.h5"])
        with h5py.File(f"{name}.h5") as f:
            estimates.append((f["robot/base_parameter_names"][()], f["identification/base_parameters"][()]))
    assert list(estimates[0][0]) == list(estimates[1][0]) and len(estimates[0][1]) >= 43
    assert np.abs(estimates[0][1] - estimates[1][1]).max() < 1e-3 * np.abs(estimates[1][1]).max()


def test_continuous_joints_get_a_range_in_the_drafted_config_and_optimize_asks_for_one(tmp_path, monkeypatch):
    """Kinova's Gen3 (continuous joints 1, 3, 5, 7): 3 of its 7 joints were moved."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "gen3.urdf").write_text(chain_urdf(["continuous", "revolute"] * 3 + ["continuous"], gripper=False))
    said = _ok(["init", "gen3.urdf"])
    problem = load_problem(tmp_path / "gen3.yaml")
    assert problem.robot.active_joints == [f"joint_{k}" for k in range(1, 8)]
    assert problem.robot.joint_ranges == {f"joint_{k}": tuple(CONTINUOUS_RANGE) for k in (1, 3, 5, 7)}
    assert "robot.joint_ranges: one turn each way" in said and "optimize would start" in said
    config = yaml.safe_load((tmp_path / "gen3.yaml").read_text())
    del config["robot"]["joint_ranges"]["joint_3"]
    (tmp_path / "gen3.yaml").write_text(yaml.safe_dump(config))
    assert_refused(
        tmp_path,
        ["check", "gen3.yaml"],
        "robot.joint_ranges: joint 'joint_3' has no range in the robot's file (continuous, or an MJCF joint without "
        "range); expected robot.joint_ranges: {joint_3: [lower, upper]}",
    )


def test_init_without_collision_reads_no_mesh(tmp_path, monkeypatch):
    """A URDF whose meshes are not installed as a ROS package: refused naming the mesh; drafted without
    capsules on request, or with them from the folder given."""
    monkeypatch.chdir(tmp_path)
    text = chain_urdf(["revolute"] * 3, gripper=False).replace(
        '<link name="link_1">',
        '<link name="link_1"><collision><geometry><mesh filename="package://arm/l1.stl"/></geometry></collision>',
    )
    (tmp_path / "arm.urdf").write_text(text)
    assert_refused(tmp_path, ["init", "arm.urdf"], "link 'link_1': collision mesh package://arm/l1.stl is not found")
    said = _ok(["init", "arm.urdf", "--no-collision"])
    assert "constraints: none: collision geometry not read" in said and "optimize would start" in said
    assert load_problem(tmp_path / "arm.yaml").constraints.self_collision is None
    (tmp_path / "description" / "arm").mkdir(parents=True)
    (tmp_path / "description" / "arm" / "l1.stl").write_text(TETRAHEDRON)
    _ok(["init", "arm.urdf", "--package-dir", "description", "--output", "found.yaml"])
    problem = load_problem(tmp_path / "found.yaml")
    assert problem.robot.package_dirs == ["description"] and problem.constraints.self_collision is not None


def test_no_home_posture_still_writes_the_config_with_what_binds_commented(tmp_path, monkeypatch):
    """The pendulum held away from hanging with 0.01 Nm efforts: no posture at rest within its torque limits."""
    monkeypatch.chdir(tmp_path)
    text = PENDULUM.format(**{**GOOD, "mimic": "", "lower": "0.5"}).replace('effort="20"', 'effort="0.01"')
    (tmp_path / "weak.urdf").write_text(text.replace('effort="5"', 'effort="0.01"'))
    said = _ok(["init", "weak.urdf"])
    assert "robot.home_posture: FIX FIRST: no posture found" in said and "limits.torque fails" in said
    assert "next: fix what it marks FIX FIRST, then excite check weak.yaml" in said
    assert "#   robot.home_posture: FIX FIRST:" in (tmp_path / "weak.yaml").read_text()
    assert_refused(tmp_path, ["check", "weak.yaml"], "limits.torque: violated before optimization, at the home posture")


def test_a_urdf_without_inertias_gets_no_torque_limit_and_a_given_one_is_refused(tmp_path, monkeypatch):
    """ROS-Industrial's KUKA iiwa has no <inertial> anywhere: every feed-forward torque was 0, silently."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "iiwa.urdf").write_text(chain_urdf(["revolute"] * 3, gripper=False).replace(CHAIN_INERTIAL, ""))
    result = runner.invoke(app, ["init", "iiwa.urdf"], env={"COLUMNS": "300"})
    assert result.exit_code == 0, result.output
    assert "gives no mass to anything joint_1, joint_2, joint_3 move(s)" in result.output  # the warning
    assert "limits.torque: none: joint_1, joint_2, joint_3 move(s) no mass in the file" in result.output
    config = yaml.safe_load((tmp_path / "iiwa.yaml").read_text())
    config["limits"]["torque"] = "urdf"
    (tmp_path / "iiwa.yaml").write_text(yaml.safe_dump(config))
    result = runner.invoke(app, ["check", "iiwa.yaml"], env={"COLUMNS": "300"})
    assert result.exit_code == 2 and "gives no mass to anything" in result.output  # warned, then refused
    assert "error: iiwa.yaml: limits.torque: joint_1, joint_2, joint_3 move(s) no mass" in result.output


def test_init_and_check_draft_an_included_framed_mjcf_arm_with_its_actuators_torque_limits(tmp_path, monkeypatch):
    """The full joint set (one joint in an included file, one in a <frame>), torque limits drafted
    from the actuators, the floor left to the world, the damping said; a missing include named."""
    monkeypatch.chdir(tmp_path)
    included_arm_mjcf(tmp_path)
    said = _ok(["init", "arm.xml"])
    config = yaml.safe_load((tmp_path / "arm.yaml").read_text())
    assert config["robot"]["active_joints"] == ["joint1", "joint2", "joint3"]
    assert config["limits"]["torque"] == "urdf" and "actuators' force ranges" in said
    assert "damping [N·m·s/rad] (joint1 0.1, joint2 0.5, joint3 0.1)" in said
    assert "optimize would start" in _ok(["check", "arm.yaml"])
    included_arm_mjcf(tmp_path, "hand.xml", "missing.xml")
    assert_refused(tmp_path, ["init", "missing.xml"], "MuJoCo cannot compile missing.xml")


def test_init_without_collision_reads_no_mesh_of_an_mjcf_either(tmp_path, monkeypatch):
    """An MJCF whose mesh files are absent (as a lab's copy of a Menagerie model often is), its bodies'
    inertias given: refused naming the mesh with collision, drafted without it (MuJoCo compiles the
    model with the mesh geoms left out), and the draft checks and runs."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "arm.xml").write_text(MESHED_ARM)
    assert_refused(tmp_path, ["init", "arm.xml"], "absent/shell.stl")
    said = _ok(["init", "arm.xml", "--no-collision"])
    assert "constraints: none: collision geometry not read" in said and "optimize would start" in said
    assert "robot.floating_base: a fixed base: no collision geometry read" in said


#: A three-joint arm whose first link's geometry is a mesh file that is not there; every body's inertia given.
MESHED_ARM = """<mujoco model="arm">
  <asset><mesh name="shell" file="absent/shell.stl"/></asset>
  <worldbody>
    <body name="upper" pos="0 0 0.1">
      <inertial pos="0 0 0.1" mass="1" diaginertia="0.01 0.01 0.001"/>
      <joint name="shoulder" axis="0 0 1" range="-2 2"/>
      <geom type="mesh" mesh="shell"/>
      <body name="fore" pos="0 0 0.2">
        <inertial pos="0 0 0.1" mass="0.8" diaginertia="0.008 0.008 0.001"/>
        <joint name="elbow" axis="0 1 0" range="-2 2"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.03"/>
        <body name="hand" pos="0 0 0.2">
          <inertial pos="0 0 0.05" mass="0.3" diaginertia="0.001 0.001 0.0005"/>
          <joint name="wrist" axis="0 1 0" range="-2 2"/>
          <geom type="box" size="0.02 0.02 0.05" pos="0 0 0.05"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
