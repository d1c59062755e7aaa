"""Where robot files come from (example-robot-data is needed only by configs that name it), and the
joint ranges a config gives."""

from importlib import metadata

import pytest
from conftest import assert_refused, pendulum_config
from typer.testing import CliRunner

import excite_cli.dynamics.robot_files as robot_files
from excite_cli.cli import app
from excite_cli.config import RobotConfig
from excite_cli.dynamics.robot_files import open_source
from excite_cli.dynamics.source import apply_joint_ranges
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

    monkeypatch.setattr(robot_files.metadata, "distribution", distribution)


def test_a_urdf_of_one_s_own_is_optimized_without_example_robot_data(tmp_path, without_example_robot_data):
    config = pendulum_config(tmp_path, changes={"optimizer.max_iterations": 5})
    result = runner.invoke(app, ["optimize", str(config), "-o", str(tmp_path / "out.h5")])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "out.h5").is_file()
    path, folders = robot_files.resolve_urdf(
        RobotConfig(urdf="pendulum.urdf", source="file", active_joints=["hinge"]), tmp_path
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
    model = open_source(tmp_path / "pendulum.urdf").model()
    with pytest.raises(ExciteError) as raised:
        apply_joint_ranges(model, ranges, "pendulum.urdf")
    assert raised.value.describe().startswith(expected)
    apply_joint_ranges(model, {"hinge": (-1.0, 0.5)}, "pendulum.urdf")  # narrower: taken
    assert (model.lowerPositionLimit[0], model.upperPositionLimit[0]) == (-1.0, 0.5)


def test_one_record_per_format_gives_the_same_robot(tmp_path):
    """The Panda as its URDF and as the MJCF MuJoCo writes of it: each format's record gives the same
    pinocchio model (masses and joint limits); an SRDF names a URDF's states, and an MJCF's refuses it."""
    from conftest import panda_mjcf

    from excite_cli.dynamics.mjcf_source import MjcfSource
    from excite_cli.dynamics.robot_files import example_robot_data_root
    from excite_cli.dynamics.urdf_source import UrdfSource

    urdf = example_robot_data_root() / "example-robot-data/robots/panda_description/urdf/panda.urdf"
    sources = [open_source(urdf), open_source(panda_mjcf(tmp_path))]
    assert [type(s) for s in sources] == [UrdfSource, MjcfSource]
    models = [s.model() for s in sources]
    masses = [[m.inertias[j].mass for j in range(1, 8)] for m in models]
    assert masses[0] == pytest.approx(masses[1], abs=1e-5)  # MuJoCo writes 6 significant digits
    assert list(models[0].lowerPositionLimit[:7]) == pytest.approx(list(models[1].lowerPositionLimit[:7]))
    srdf = tmp_path / "panda.srdf"
    ready = '<group_state name="ready" group="arm"><joint name="panda_joint4" value="-2.4"/></group_state>'
    srdf.write_text(f'<robot name="panda">{ready}</robot>')
    assert sources[0].with_srdf(srdf).named_states() == {"ready": {"panda_joint4": -2.4}}
    with pytest.raises(ExciteError, match="srdf: names the states of a URDF; panda.xml is an MJCF"):
        sources[1].with_srdf(srdf)
