"""``check`` on an identify config: every run read as identify reads it and summarized, the base and
the effects that would be fitted; what identify would refuse is refused the same way."""

import pytest
import yaml
from conftest import assert_refused, pendulum_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import ConfigKind, load_config
from excite_cli.workflows.check_identify import plan_identify

runner = CliRunner()


@pytest.fixture(scope="module")
def identify_config(tmp_path_factory):
    """A pendulum result, one simulated run of it (100 Hz, 1 period of 10 s) and an identify config."""
    folder = tmp_path_factory.mktemp("check_identify")
    assert runner.invoke(app, ["optimize", str(pendulum_config(folder))]).exit_code == 0
    effects = {"sample_rate": 100.0, "periods": 1, "torque_noise": 0.01, "seed": 1}
    (folder / "effects.yaml").write_text(yaml.safe_dump(effects))
    argv = ["simulate", str(folder / "out.h5"), str(folder / "effects.yaml"), "-o", str(folder / "runs")]
    assert runner.invoke(app, argv).exit_code == 0
    config = {
        "robot": {"urdf": "pendulum.urdf", "active_joints": ["hinge"]},
        "data": {"runs": [{"file": "runs/run_1.csv"}], "columns": {"q": ["q_hinge"], "tau": ["tau_hinge"]}},
        "identification": {"declared_effects": {"hinge": ["viscous"]}},
    }
    (folder / "id.yaml").write_text(yaml.safe_dump(config))
    return folder / "id.yaml"


def test_each_run_is_summarized_as_identify_reads_it(identify_config):
    plan = plan_identify(load_config(identify_config, None, ConfigKind.IDENTIFY))
    [run] = plan.runs
    assert (run.samples, run.seconds, run.signals, run.role) == (1001, pytest.approx(10.0), ("q", "tau"), "blocks")
    assert run.rate == pytest.approx(100.0)
    assert plan.joints == ["hinge"] and plan.base_parameters == 3  # m·z, m·x and I_yy of the arm, its tip held
    assert plan.declared == ["viscous hinge"] and plan.candidates > 0


def test_check_says_identify_would_start(identify_config):
    result = runner.invoke(app, ["check", str(identify_config)], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "Runs, read as identify reads them" in result.output and result.output.strip().endswith(
        "identify would start"
    )


def test_check_refuses_what_identify_would_refuse(identify_config, tmp_path):
    config = yaml.safe_load(identify_config.read_text())
    config["data"]["columns"]["tau"] = ["tau_elbow"]
    (identify_config.parent / "bad.yaml").write_text(yaml.safe_dump(config))
    assert_refused(tmp_path, ["check", str(identify_config.parent / "bad.yaml")], "no column 'tau_elbow'")
    config = yaml.safe_load(identify_config.read_text())
    config["data"]["runs"][0]["payload"] = {"mass": 1.0, "frame": "gripper"}  # identify refused it at once
    (identify_config.parent / "payload.yaml").write_text(yaml.safe_dump(config))
    expected = "data.runs[0].payload.frame: 'gripper' is not a frame of the robot's model"
    assert_refused(tmp_path, ["check", str(identify_config.parent / "payload.yaml")], expected)
    config["data"]["runs"][0]["payload"] = {"mass": 1e30}  # the SDP ended infeasible, naming the fit
    (identify_config.parent / "payload.yaml").write_text(yaml.safe_dump(config))
    assert_refused(tmp_path, ["check", str(identify_config.parent / "payload.yaml")], "data.runs.0.payload.mass")
    urdf_out = str(tmp_path / "model.urdf")
    mjcf = identify_config.parent / "arm.xml"
    mjcf.write_text(
        '<mujoco model="arm"><compiler angle="radian"/><worldbody><body name="arm"><joint name="hinge" '
        'type="hinge" axis="0 1 0" range="-2 2"/><geom type="sphere" size="0.1" mass="1"/></body></worldbody></mujoco>'
    )
    config = yaml.safe_load(identify_config.read_text())
    config["robot"]["urdf"] = "arm.xml"
    (identify_config.parent / "mjcf.yaml").write_text(yaml.safe_dump(config))
    argv = ["identify", str(identify_config.parent / "mjcf.yaml"), "-o", str(tmp_path / "r.h5"), "--urdf-out", urdf_out]
    assert_refused(tmp_path, argv, "--urdf-out: the robot's file arm.xml is an MJCF")  # before the fit, not after
    assert_refused(tmp_path, ["check", str(identify_config), "-k", "2"], "--iterations: applies to an optimize config")


def test_a_config_with_data_beside_optimize_sections_is_named_as_both(identify_config, tmp_path):
    """Issue 62: an optimize config with a stray data section was read as an identify config and
    refused on its limits section."""
    config = yaml.safe_load(identify_config.read_text())
    config["limits"], config["trajectory"] = {"position_margin": 0.1}, {"harmonics": 3}
    (identify_config.parent / "both.yaml").write_text(yaml.safe_dump(config))
    assert_refused(tmp_path, ["check", str(identify_config.parent / "both.yaml")], "beside the optimize section(s)")
