"""`excite init` on an arm no shipped config uses (the UR3 of example-robot-data): the written config
passes the dry run, its home posture is inside the URDF's limits with every link mesh apart (but the
pairs it excluded, each with its reason) and above the mounting plane (pinocchio and coal on the
meshes, not the capsules); the identify kind; bad input in one line."""

import coal
import h5py
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import GOOD, PENDULUM, assert_refused, pendulum_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.design.noise import typical_torques
from excite_cli.design.resolve import build_excitation
from excite_cli.drafting.noise_source import CURRENT_FLOOR, RELATIVE
from excite_cli.dynamics.robot_files import example_robot_data_root
from excite_cli.identification.config import IdentifyProblem
from excite_cli.workflows.init import run_init

UR3 = "ur_description/urdf/ur3_robot.urdf"
runner = CliRunner()


@pytest.fixture(scope="module")
def ur3(tmp_path_factory):
    target = tmp_path_factory.mktemp("init") / "ur3.yaml"
    return run_init(UR3, target)


def _meshes(problem):
    share = example_robot_data_root()
    path = str(share / "example-robot-data" / "robots" / problem.robot.urdf)
    model = pin.buildModelFromUrdf(path)
    geometry = pin.buildGeomFromUrdf(model, path, pin.COLLISION, package_dirs=[str(share)])
    return model, geometry


def test_the_written_config_passes_the_dry_run_with_a_home_posture_every_mesh_accepts(ur3):
    problem = load_problem(ur3.target)
    assert ur3.plan is not None and ur3.plan.excitation.robot.joint_names == problem.robot.active_joints
    assert len(problem.robot.active_joints) == 6 and problem.limits.torque == "urdf"
    model, geometry = _meshes(problem)
    q = np.array([problem.robot.home_posture[n] for n in model.names[1:]])
    assert np.all(q >= model.lowerPositionLimit + problem.limits.position_margin - 1e-9)
    assert np.all(q <= model.upperPositionLimit - problem.limits.position_margin + 1e-9)
    for name in problem.robot.active_joints:  # half the URDF's velocity limit
        assert problem.limits.velocity[name] == pytest.approx(0.5 * model.velocityLimit[model.getJointId(name) - 1])
    excluded = {frozenset(p) for p in problem.constraints.self_collision.exclude_pairs}
    text = ur3.target.read_text()
    for a, b in problem.constraints.self_collision.exclude_pairs:
        assert f"excluded pair {a} – {b}: " in text  # with its reason
    geometry.addAllCollisionPairs()  # before its data, which sizes its results by the pairs
    data, geometry_data = model.createData(), pin.GeometryData(geometry)
    link = {k: model.frames[g.parentFrame].name for k, g in enumerate(geometry.geometryObjects)}
    joint = {k: g.parentJoint for k, g in enumerate(geometry.geometryObjects)}
    pin.computeDistances(model, data, geometry, geometry_data, q)
    for pair, result in zip(geometry.collisionPairs, geometry_data.distanceResults):
        a, b = pair.first, pair.second
        if joint[a] == joint[b] or abs(joint[a] - joint[b]) == 1 or frozenset((link[a], link[b])) in excluded:
            continue  # one body, adjacent bodies, or excluded with a reason
        assert result.min_distance > 0, (link[a], link[b])
    # every moving link's mesh (coal) above the mounting plane, but those the file says it ignores
    point = problem.constraints.environment.shapes[0].point
    plane = coal.Halfspace(np.array([0.0, 0.0, 1.0]), point[2])  # z ≤ point: the table
    ignored = set(problem.constraints.environment.ignore_links)
    pin.updateGeometryPlacements(model, data, geometry, geometry_data, q)
    for k, g in enumerate(geometry.geometryObjects):
        if g.parentJoint > 0 and link[k] not in ignored:
            placed = coal.Transform3s(geometry_data.oMg[k].rotation, geometry_data.oMg[k].translation)
            result = coal.DistanceResult()
            coal.distance(g.geometry, placed, plane, coal.Transform3s(), coal.DistanceRequest(), result)
            assert result.min_distance > 0, link[k]


def test_the_identify_kind_names_the_columns_simulate_writes_and_what_to_fill_in(tmp_path):
    run = run_init(UR3, tmp_path / "id.yaml", kind="identify")
    problem = load_problem(run.target, IdentifyProblem)
    assert problem.data.columns.q == [f"q_{j}" for j in problem.robot.active_joints]
    assert problem.data.columns.tau == [f"tau_{j}" for j in problem.robot.active_joints]
    assert run.plan is None and "FILL IN" in run.target.read_text()
    assert "run `excite identify`" in run.target.read_text() and "excite check" not in run.target.read_text()
    assert problem.preprocessing.sample_rate is None  # min(200 Hz, the data's): a 195 Hz file is not refused
    assert_refused(tmp_path, ["identify", str(run.target)], "runs/run_1.csv")  # not there yet


def test_a_file_with_the_columns_gets_them_filled_in_and_nothing_to_fill(tmp_path):
    """A lab file whose columns are time_s, <joint>_pos, <joint>_vel, Effort_<joint> (any case)."""
    names = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint"]
    names += ["wrist_3_joint"]
    header = ["time_s"] + [f"{j}_pos" for j in names] + [f"{j}_vel" for j in names] + [f"Effort_{j}" for j in names]
    (tmp_path / "lab.csv").write_text(",".join(header) + "\n" + ",".join(["0"] * len(header)) + "\n")
    run = run_init(UR3, tmp_path / "id.yaml", kind="identify", runs=[str(tmp_path / "lab.csv")])
    columns = load_problem(run.target, IdentifyProblem).data.columns
    assert columns.time == "time_s" and columns.q == [f"{j}_pos" for j in names]
    assert columns.qd == [f"{j}_vel" for j in names] and columns.tau == [f"Effort_{j}" for j in names]
    text = run.target.read_text()
    assert "FILL IN" not in text and "time, q, qd, tau recognized in lab.csv" in text
    (tmp_path / "other.csv").write_text("time,a,b\n0,1,2\n")
    other = run_init(UR3, tmp_path / "id2.yaml", kind="identify", runs=[str(tmp_path / "other.csv")])
    assert "FILL IN: the column names of your files for q, tau" in other.target.read_text()


def test_recorded_bags_get_a_config_without_columns_that_identifies_the_friction(tmp_path, monkeypatch):
    """A pendulum run simulated as ``ros2 bag record /joint_states`` writes it (viscous 0.2 Nm·s/rad),
    ``init --kind identify --runs``, then ``identify``: the bag is read by joint name and the viscous
    friction comes back within 5 %."""
    monkeypatch.chdir(tmp_path)
    config = pendulum_config(tmp_path, changes={"optimizer.max_iterations": 30})
    assert runner.invoke(app, ["optimize", str(config)]).exit_code == 0
    effects = {"sample_rate": 200.0, "periods": 3, "torque_noise": 0.01, "seed": 2, "recording": "rosbag2"}
    (tmp_path / "effects.yaml").write_text(yaml.safe_dump({**effects, "effects": {"viscous": {"*": 0.2}}}))
    assert runner.invoke(app, ["simulate", "out.h5", "effects.yaml", "-o", "bags"]).exit_code == 0
    assert sorted(p.name for p in (tmp_path / "bags" / "run_1").iterdir()) == ["metadata.yaml", "run_1.db3"]
    argv = ["init", "pendulum.urdf", "--kind", "identify", "--joints", "hinge", "--runs", "bags/run_1", "-o", "id.yaml"]
    result = runner.invoke(app, argv)
    assert result.exit_code == 0 and "next: excite identify id.yaml" in result.output, result.output
    problem = load_problem(tmp_path / "id.yaml", IdentifyProblem)
    assert problem.data.columns is None and problem.data.runs[0].file == "bags/run_1"
    result = runner.invoke(app, ["identify", "id.yaml", "-o", "report.h5"])
    assert result.exit_code == 0, result.output
    with h5py.File(tmp_path / "report.h5") as f:
        found = {(r["effect"].decode(), r["joint"].decode()): r["value"] for r in f["identification/effects"][()]}
    assert found[("viscous", "hinge")] == pytest.approx(0.2, rel=0.05)
    # a bag and a CSV file in one config: the columns are the file's, the bag's joints matched by name
    friction = {"effects": {"viscous": {"*": 0.2}}}
    (tmp_path / "effects.yaml").write_text(yaml.safe_dump({**effects, **friction, "recording": "csv", "seed": 3}))
    assert runner.invoke(app, ["simulate", "out.h5", "effects.yaml", "-o", "csvs"]).exit_code == 0
    argv[-3:] = ["bags/run_1", "--runs", "csvs/run_1.csv", "-o", "mixed.yaml"]
    assert runner.invoke(app, argv).exit_code == 0
    mixed = load_problem(tmp_path / "mixed.yaml", IdentifyProblem).data
    assert [r.file for r in mixed.runs] == ["bags/run_1", "csvs/run_1.csv"] and mixed.columns.q == ["q_hinge"]
    result = runner.invoke(app, ["check", "mixed.yaml"])
    assert result.exit_code == 0, result.output
    result = runner.invoke(app, ["identify", "mixed.yaml", "-o", "mixed.h5"])
    assert result.exit_code == 0, result.output
    with h5py.File(tmp_path / "mixed.h5") as f:
        found = {(r["effect"].decode(), r["joint"].decode()): r["value"] for r in f["identification/effects"][()]}
    assert found[("viscous", "hinge")] == pytest.approx(0.2, rel=0.05)


@pytest.mark.parametrize(
    "argv, expected",
    [
        (
            ["init", UR3, "--runs", "x.csv"],
            "--runs: are the measured runs of an identify config; expected kind identify",
        ),
        (["init", UR3, "--kind", "identify", "--runs", "none.csv"], "none.csv"),
        (
            ["init", UR3, "--kind", "identify", "--runs", "csvs"],
            "runs: csvs is a folder, not a data file or a ROS 2 bag (no metadata.yaml in it); "
            "expected each data file named as a run of its own",
        ),
        (["init", UR3, "--joints", "elbow_joint,nope"], "'nope' is not a 1-DoF joint of ur3_robot.urdf"),
        (
            ["init", "nothing/here.urdf"],
            "URDF or MJCF (a file, or a path inside example-robot-data's robots folder) not found",
        ),
        (["init", UR3, "--kind", "simulate"], "'simulate' is not a config kind"),
        (
            ["init", UR3, "--torque-from", "battery"],
            "--torque-from: 'battery' is not a torque source; expected sensor, current, unknown",
        ),
        (
            ["init", UR3, "--kind", "identify", "--torque-from", "current"],
            "--torque-from: drafts the noise section of an optimize config; this is kind identify",
        ),
        (["init", UR3, "-o", "taken.yaml"], "taken.yaml exists"),
        (
            ["init", "arm.urdf.xacro"],
            "urdf: arm.urdf.xacro is a xacro file: its macros are not expanded; expected the URDF it expands to",
        ),
    ],
)
def test_bad_init_input_is_one_line_and_writes_nothing(tmp_path, monkeypatch, argv, expected):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "taken.yaml").write_text("keep: me\n")
    (tmp_path / "csvs").mkdir()
    (tmp_path / "csvs" / "run_1.csv").write_text("time,q_elbow_joint\n0,0\n")
    (tmp_path / "arm.urdf.xacro").write_text('<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro"/>\n')
    assert_refused(tmp_path, argv, expected)
    assert (tmp_path / "taken.yaml").read_text() == "keep: me\n"


def test_init_prints_its_assumptions_and_the_dry_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["init", UR3, "--joints", "shoulder_pan_joint", "--joints", "elbow_joint"])
    assert result.exit_code == 0, result.output
    assert "wrote ur3_robot.yaml" in result.output and "robot.active_joints: the joints given" in result.output
    assert "robot.home_posture: searched" in result.output and "next: excite optimize ur3_robot.yaml" in result.output
    assert load_problem(tmp_path / "ur3_robot.yaml").robot.active_joints == ["shoulder_pan_joint", "elbow_joint"]


def test_an_unknown_torque_source_drafts_no_noise_and_says_so(ur3):
    assert load_problem(ur3.target).noise is None
    assert "noise: none: the torque source was not said" in ur3.target.read_text()


def test_torque_from_current_drafts_noise_growing_with_the_torque_on_the_panda(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["init", "panda_description/urdf/panda.urdf", "--torque-from", "current"])
    assert result.exit_code == 0, result.output
    problem = load_problem(tmp_path / "panda.yaml")
    typical = typical_torques(build_excitation(problem))
    drafted = np.array([problem.noise.absolute[j] for j in problem.robot.active_joints])
    assert problem.noise.relative == RELATIVE
    np.testing.assert_allclose(drafted, CURRENT_FLOOR * typical, rtol=5e-3)
    assert "noise: torque from motor current: 2% of the torque" in result.output


def test_a_urdf_file_without_collision_geometry_gets_no_collision_constraint(tmp_path):
    (tmp_path / "pendulum.urdf").write_text(PENDULUM.format(**{**GOOD, "mimic": ""}))
    run = run_init(str(tmp_path / "pendulum.urdf"), tmp_path / "configs" / "pendulum.yaml")
    problem = load_problem(run.target)
    assert (problem.robot.urdf, problem.robot.source) == ("../pendulum.urdf", "file")  # beside the config
    assert problem.constraints.self_collision is None and problem.constraints.environment is None
    assert "constraints: none: the file has no collision geometry" in run.target.read_text()
    assert run.plan.excitation.robot.joint_names == ["hinge", "tip_joint"]
