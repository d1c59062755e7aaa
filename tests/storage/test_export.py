"""The played file: CSV, NPZ and a ROS 2 goal written from the same samples and read back."""

import numpy as np
import pytest
import yaml

from excite_cli.errors import ExciteError
from excite_cli.storage.export import Export, columns, write_export
from excite_cli.storage.formats import FORMATS

JOINTS = ["a", "b"]


@pytest.fixture
def export():
    t = np.arange(5) / 100.0
    q = np.column_stack([np.sin(t), np.cos(t)])
    return Export(JOINTS, t, q, 2 * q, 3 * q, 4 * q, 100.0, 2, 1, [("trajectory", 0.0, 0.05)], -0.01, "none")


def test_csv_and_npz_hold_the_same_samples_under_their_column_names(export, tmp_path):
    table = np.genfromtxt(write_export(tmp_path / "m.csv", export, "csv"), delimiter=",", names=True, skip_header=4)
    assert (
        list(table.dtype.names)
        == columns(JOINTS)
        == [
            "time_s",
            "q_a_rad",
            "q_b_rad",
            "qd_a_rad_s",
            "qd_b_rad_s",
            "qdd_a_rad_s2",
            "qdd_b_rad_s2",
            "tau_a_Nm",
            "tau_b_Nm",
        ]
    )
    np.testing.assert_allclose(table["tau_b_Nm"], export.tau[:, 1], rtol=1e-9)
    archive = np.load(write_export(tmp_path / "m.npz", export, "npz"))
    np.testing.assert_array_equal(archive["qdd"], export.qdd)
    assert archive["joint_names"].tolist() == JOINTS


def test_a_ros2_goal_has_one_point_per_sample_with_its_time(export, tmp_path):
    goal = yaml.safe_load(write_export(tmp_path / "m.yaml", export, "ros2").read_text())
    trajectory = goal["trajectory"]
    assert trajectory["joint_names"] == JOINTS and len(trajectory["points"]) == 5
    last = trajectory["points"][-1]
    assert last["time_from_start"] == {"sec": 0, "nanosec": 40_000_000}
    np.testing.assert_allclose(last["effort"], export.tau[-1])


def test_an_unknown_format_writes_nothing(export, tmp_path):
    with pytest.raises(ExciteError, match="format"):
        write_export(tmp_path / "m.xml", export, "xml")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_every_format_the_help_lists_is_written_with_its_ending(export, tmp_path, fmt):
    path = write_export(tmp_path / f"m.{FORMATS[fmt]}", export, fmt)
    assert path.exists() and path.suffix == f".{FORMATS[fmt]}" and path.stat().st_size > 0
