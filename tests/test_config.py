"""Bad input gets one line naming the field, a non-zero exit and no traceback or output file."""

import copy
from pathlib import Path

import pytest
import yaml
from conftest import UR5, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config import Problem, effective_yaml, resolve_path
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.errors import ExciteError

runner = CliRunner()


def _cli_error(tmp_path, data, *extra):
    path = write_config(tmp_path, data)
    result = runner.invoke(app, ["optimize", str(path), "--output", str(tmp_path / "out.h5"), *extra])
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    assert not (tmp_path / "out.h5").exists()
    lines = [line for line in result.output.strip().splitlines() if line.strip()]
    return " ".join(lines)


def test_misspelled_joint_names_the_field_and_suggests(tmp_path):
    data = copy.deepcopy(UR5)
    data["robot"]["active_joints"][2] = "elbow_jiont"
    message = _cli_error(tmp_path, data)
    assert "robot.active_joints" in message and "elbow_jiont" in message and "elbow_joint" in message


def test_negative_period_names_the_field(tmp_path):
    data = copy.deepcopy(UR5)
    data["trajectory"]["cost_period"] = -0.2
    message = _cli_error(tmp_path, data)
    assert "trajectory.cost_period" in message and "greater than 0" in message


@pytest.mark.parametrize(
    "edit, field",
    [
        (lambda d: d["limits"].pop("acceleration"), "limits.acceleration"),
        (lambda d: d["trajectory"].update(harmonix=3), "trajectory.harmonix"),
        (lambda d: d["limits"].update(position_margin=4.0), "limits.position_margin"),
        (lambda d: d["limits"].update(position_margin={"elbow_joint": -0.1}), "limits.position_margin"),
        (lambda d: d["limits"].update(position_margin={"wrist_9_joint": 0.1}), "limits.position_margin"),
        (lambda d: d["limits"].update(velocity={"wrist_9_joint": 1.0}), "limits.velocity"),
        (lambda d: d["limits"].update(acceleration=-1.0), "limits.acceleration"),
        (lambda d: d["robot"].update(urdf="nowhere/robot.urdf"), "robot.urdf"),
        (lambda d: d["robot"].update(locked_joints={"shoulder_pan_joint": 0.0}), "robot.locked_joints"),
        (
            lambda d: (
                d["sequence"].update(prior="missing.h5")
                if "sequence" in d
                else d.update(sequence={"prior": "missing.h5"})
            ),
            "sequence.prior",
        ),
    ],
)
def test_bad_fields_are_named(tmp_path, edit, field):
    data = copy.deepcopy(UR5)
    edit(data)
    assert field in _cli_error(tmp_path, data)


def test_malformed_yaml_and_missing_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("robot: [unclosed\n")
    result = runner.invoke(app, ["optimize", str(bad)])
    assert result.exit_code == 2 and "malformed YAML" in result.output and "Traceback" not in result.output
    result = runner.invoke(app, ["optimize", str(tmp_path / "none.yaml")])
    assert result.exit_code == 2 and "not found" in result.output


def test_velocity_defaults_to_the_urdf(tmp_path):
    problem = load_problem(write_config(tmp_path, UR5))
    excitation = build_excitation(problem)
    assert excitation.limits.upper[1].tolist() == pytest.approx([3.15, 3.15, 3.15, 3.2, 3.2, 3.2])


def test_library_raises_the_same_error(tmp_path):
    data = copy.deepcopy(UR5)
    data["robot"]["active_joints"] = ["nope"]
    with pytest.raises(ExciteError, match="robot.active_joints"):
        build_excitation(load_problem(write_config(tmp_path, data)))


def test_paths_are_relative_to_the_config_file_and_the_effective_config_is_complete(tmp_path):
    problem = load_problem(write_config(tmp_path, UR5))
    assert problem.folder == tmp_path
    assert resolve_path("prior.h5", problem.folder) == tmp_path / "prior.h5"
    assert resolve_path("/data/prior.h5", problem.folder) == Path("/data/prior.h5")
    assert resolve_path("prior.h5", None) == Path("prior.h5")
    stored = yaml.safe_load(effective_yaml(problem))
    assert stored["optimizer"]["objective"] == "log_trace_inverse" and stored["optimizer"]["scaling"] == "urdf"
    assert Problem.model_validate(stored).model_dump() == problem.model_dump()  # what ran can be run again
