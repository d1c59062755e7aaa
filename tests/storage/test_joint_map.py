"""Joints renamed as the controller names them, in every format, active and held alike; a map that
names a joint the export does not have, or gives two joints one name, is refused naming it."""

from dataclasses import replace

import numpy as np
import pytest
import yaml

from excite_cli.design.held_joints import HeldTorques
from excite_cli.errors import ExciteError
from excite_cli.storage.export import Export
from excite_cli.storage.export_files import write_export
from excite_cli.storage.joint_map import read_joint_map, renamed


@pytest.fixture
def standing():
    t = np.arange(5) / 100.0
    q = np.column_stack([np.sin(t), np.cos(t)])
    qd = 2 * q
    qd[-1] = 0.0
    export = Export(["joint1", "joint2"], t, q, qd, 3 * q, 4 * q, 100.0, 2, 1, [("trajectory", 0.0, 0.05)], -0.01, "")
    tau = np.column_stack([np.linspace(1.0, 2.0, 5), np.linspace(-3.0, -1.0, 5)])
    held = HeldTorques(
        ("knee", "hip"), np.array([0.1, -0.2]), tau, np.zeros((5, 4, 3)), np.zeros((4, 3)), np.array([50.0, 0.0]), 0
    )
    return replace(export, held=held)


def test_inline_and_file_maps_rename_the_joints_in_the_controller_s_trajectory_and_the_csv(standing, tmp_path):
    inline = read_joint_map("joint1=fr3_joint1, joint2=fr3_joint2,knee=left_knee_joint")
    (tmp_path / "names.yaml").write_text(yaml.safe_dump(inline))
    assert read_joint_map(str(tmp_path / "names.yaml")) == inline
    export = renamed(standing, inline)
    goal = yaml.safe_load(write_export(tmp_path / "e.yaml", export, "ros2", True).read_text())["trajectory"]
    assert goal["joint_names"] == ["fr3_joint1", "fr3_joint2", "left_knee_joint", "hip"]
    header = [
        line
        for line in write_export(tmp_path / "m.csv", export, "csv").read_text().splitlines()
        if not line.startswith("#")
    ][0]
    assert "q_fr3_joint1_rad" in header and "tau_left_knee_joint_Nm" in header and "q_joint1" not in header
    np.testing.assert_array_equal(export.q, standing.q)


def test_a_map_naming_an_unknown_joint_or_one_name_twice_is_refused(standing, tmp_path):
    with pytest.raises(ExciteError, match="'joint7' is not a joint of the export") as info:
        renamed(standing, {"joint7": "a"})
    assert "joint1, joint2, knee, hip" in info.value.expected
    with pytest.raises(ExciteError, match="two joints would be called 'hip'"):
        renamed(standing, {"knee": "hip"})
    with pytest.raises(ExciteError, match="'joint1' is not robot=controller"):
        read_joint_map("joint1")
    with pytest.raises(ExciteError, match=r"'joint1' is named twice \(joint1=a, joint1=b\)"):
        read_joint_map("joint1=a, joint2=c, joint1=b")
    (tmp_path / "twice.yaml").write_text("joint1: a\njoint1: b\n")
    with pytest.raises(ExciteError, match="joint1"):  # the YAML form refuses it too
        read_joint_map(str(tmp_path / "twice.yaml"))
    with pytest.raises(ExciteError, match="'fr3 joint1' is not a joint name a controller can hold"):
        read_joint_map("joint1=fr3 joint1")
    (tmp_path / "list.yaml").write_text("[a, b]\n")
    with pytest.raises(ExciteError, match="list.yaml is not one mapping of joint names"):
        read_joint_map(str(tmp_path / "list.yaml"))
