"""The meshes of a URDF: found where ROS and pinocchio look, and checked before assimp reads them."""

import os
from pathlib import Path

import pinocchio as pin
import pytest

from excite_cli.config import RobotConfig
from excite_cli.dynamics.robot_files import example_robot_data_root, resolve_urdf
from excite_cli.dynamics.urdf_meshes import MAX_MESH_BYTES, check_meshes, collision_geometry, mesh_path, package_folders
from excite_cli.errors import ExciteError

#: An ASCII STL of one triangle.
BOX = (
    "solid box\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n"
)


def _robot(folder: Path, mesh: str) -> Path:
    """``folder/my_robot/urdf/robot.urdf``: a base and one link whose collision mesh is ``mesh``."""
    urdf = folder / "my_robot" / "urdf" / "robot.urdf"
    urdf.parent.mkdir(parents=True)
    urdf.write_text(
        '<robot name="r"><link name="base"/><link name="arm"><collision><geometry>'
        f'<mesh filename="{mesh}"/></geometry></collision></link>'
        '<joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    return urdf


def test_a_package_uri_is_found_from_the_urdf_s_own_package(tmp_path):
    """The URDF inside its package, given as a file: the folder above the package holds it."""
    urdf = _robot(tmp_path, "package://my_robot/meshes/arm.stl")
    (tmp_path / "my_robot" / "meshes").mkdir()
    (tmp_path / "my_robot" / "meshes" / "arm.stl").write_text(BOX)
    folders = package_folders(urdf, [str(urdf.parent)])
    assert str(tmp_path) in folders
    assert mesh_path("package://my_robot/meshes/arm.stl", urdf, folders) == tmp_path / "my_robot/meshes/arm.stl"
    geometry = collision_geometry(pin.buildModelFromUrdf(str(urdf)), urdf, folders)
    assert geometry.ngeoms == 1


def test_file_uris_absolute_and_relative_names_are_resolved(tmp_path):
    urdf = _robot(tmp_path, "arm.stl")
    (urdf.parent / "arm.stl").write_text(BOX)
    assert mesh_path("arm.stl", urdf, []) == urdf.parent / "arm.stl"
    assert mesh_path(f"file://{urdf.parent / 'arm.stl'}", urdf, []) == urdf.parent / "arm.stl"
    assert mesh_path(str(urdf.parent / "arm.stl"), urdf, []) == urdf.parent / "arm.stl"
    assert mesh_path("other.stl", urdf, []) is None


def test_a_fifo_mesh_is_refused_before_anything_reads_it(tmp_path):
    urdf = _robot(tmp_path, "arm.stl")
    os.mkfifo(urdf.parent / "arm.stl")
    with pytest.raises(ExciteError, match="link 'arm': collision mesh arm.stl: .* is a FIFO"):
        check_meshes(urdf, [])


def test_a_mesh_beyond_the_size_bound_is_refused_by_its_size(tmp_path):
    urdf = _robot(tmp_path, "arm.stl")
    with open(urdf.parent / "arm.stl", "wb") as f:
        f.truncate(MAX_MESH_BYTES + 1)  # sparse
    with pytest.raises(ExciteError, match="collision mesh arm.stl is 200 MB, more than the 200 MB"):
        check_meshes(urdf, [])


def test_a_file_that_is_not_a_mesh_is_one_line_naming_the_urdf(tmp_path):
    urdf = _robot(tmp_path, "arm.stl")
    (urdf.parent / "arm.stl").write_bytes(b"\x00\x01 not a mesh")
    with pytest.raises(ExciteError, match="cannot load the collision meshes of robot.urdf") as caught:
        collision_geometry(pin.buildModelFromUrdf(str(urdf)), urdf, [])
    assert "\n" not in str(caught.value)


ARMS = [
    "panda_description/urdf/panda.urdf",
    "ur_description/urdf/ur3_robot.urdf",
    "ur_description/urdf/ur10_robot.urdf",
    "kinova_description/robots/kinova.urdf",
    "xarm_description/urdf/xarm7.urdf",
    "z1_description/urdf/z1.urdf",
    "so_arm_description/urdf/so101.urdf",
    "baxter_description/urdf/baxter.urdf",  # package://example-robot-data/...: "could not be found" before
    "tiago_description/robots/tiago.urdf",
]


@pytest.mark.parametrize("arm", ARMS)
def test_every_arm_example_robot_data_ships_loads_its_meshes_given_as_a_file(arm, tmp_path):
    """The URDF named by its path (``source: file``, as a lab passes its own): its ``package://``
    meshes are found from the URDF's own package and example-robot-data's folder."""
    urdf = example_robot_data_root() / "example-robot-data" / "robots" / arm
    path, folders = resolve_urdf(RobotConfig.model_construct(urdf=str(urdf), source="file"), tmp_path)
    geometry = collision_geometry(pin.buildModelFromUrdf(str(path)), path, folders)
    assert geometry.ngeoms > 0


def test_a_mesh_of_a_package_installed_elsewhere_is_named_with_where_excite_looked(tmp_path, monkeypatch):
    """An expanded vendor URDF whose ``package://`` meshes are not installed as a ROS package: the
    refusal names the mesh and every folder looked in; ``robot.package_dirs`` names where it is."""
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    urdf = _robot(tmp_path, "package://vendor_description/meshes/arm.stl")
    cfg = RobotConfig(urdf="my_robot/urdf/robot.urdf", active_joints=["j"])
    path, folders = resolve_urdf(cfg, tmp_path)
    with pytest.raises(ExciteError) as refused:
        check_meshes(path, folders)
    said = refused.value.describe()
    assert "link 'arm': collision mesh package://vendor_description/meshes/arm.stl is not found; looked in" in said
    assert (
        str(urdf.parent) in said
        and "robot.package_dirs: the folder that holds the package 'vendor_description'" in said
    )
    (tmp_path / "downloads" / "vendor_description" / "meshes").mkdir(parents=True)
    (tmp_path / "downloads" / "vendor_description" / "meshes" / "arm.stl").write_text(BOX)
    given = RobotConfig(urdf="my_robot/urdf/robot.urdf", active_joints=["j"], package_dirs=["downloads"])
    path, folders = resolve_urdf(given, tmp_path)
    assert collision_geometry(pin.buildModelFromUrdf(str(path)), path, folders).ngeoms == 1
