"""Where robot files come from (example-robot-data is needed only by configs that name it), and the
joint ranges a config gives."""

from importlib import metadata

import pytest
from conftest import assert_refused, pendulum_config
from typer.testing import CliRunner

import excite_cli.dynamics.urdf_source as urdf_source
from excite_cli.cli import app
from excite_cli.dynamics.urdf_source import apply_joint_ranges, robot_model
from excite_cli.errors import ExciteError

runner = CliRunner()


@pytest.fixture
def without_example_robot_data(monkeypatch):
    """example-robot-data as if it were not installed (its distribution not found)."""
    real = metadata.distribution

    def distribution(name):
        if name == "example-robot-data":
            raise metadata.PackageNotFoundError(name)
        return real(name)

    monkeypatch.setattr(urdf_source.metadata, "distribution", distribution)


def test_a_urdf_of_one_s_own_is_optimized_without_example_robot_data(tmp_path, without_example_robot_data):
    config = pendulum_config(tmp_path, changes={"optimizer.max_iterations": 5})
    result = runner.invoke(app, ["optimize", str(config), "-o", str(tmp_path / "out.h5")])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "out.h5").is_file()
    path, folders = urdf_source.resolve_urdf(
        urdf_source.RobotConfig(urdf="pendulum.urdf", source="file", active_joints=["hinge"]), tmp_path
    )
    assert path == tmp_path / "pendulum.urdf" and "cmeel.prefix" not in " ".join(folders)


def test_a_shipped_config_without_example_robot_data_is_one_line(tmp_path, without_example_robot_data):
    argv = ["check", "configs/panda.yaml"]
    assert_refused(tmp_path, argv, "robot.source: example-robot-data is not installed")


@pytest.mark.parametrize(
    "ranges, expected",
    [
        ({"elbow": (-1.0, 1.0)}, "robot.joint_ranges.elbow: 'elbow' is not a 1-DoF joint of pendulum.urdf"),
        ({"hinge": (1.0, 1.0)}, "robot.joint_ranges.hinge: [1, 1] is empty; expected lower < upper"),
        ({"hinge": (-3.0, 1.0)}, "robot.joint_ranges.hinge: [-3, 1] reaches past the limits in pendulum.urdf, [-2, 2]"),
    ],
)
def test_a_joint_range_that_cannot_be_is_named(tmp_path, ranges, expected):
    pendulum_config(tmp_path)
    model = robot_model(tmp_path / "pendulum.urdf")
    with pytest.raises(ExciteError) as raised:
        apply_joint_ranges(model, ranges, "pendulum.urdf")
    assert raised.value.describe().startswith(expected)
    apply_joint_ranges(model, {"hinge": (-1.0, 0.5)}, "pendulum.urdf")  # narrower: taken
    assert (model.lowerPositionLimit[0], model.upperPositionLimit[0]) == (-1.0, 0.5)
