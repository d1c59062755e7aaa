"""The 3D scene of a motion: every collision mesh, the world shapes, and one animation frame per
posture at the meshes' placements by pinocchio's forward kinematics. The scene's commands are
meshcat's msgpack, base64 in the HTML file, decoded here."""

import base64
import re

import numpy as np
import pinocchio as pin
import pytest
import umsgpack
from conftest import CONFIGS, robot_of

from excite_cli.collision.world import world_shapes
from excite_cli.config import EnvironmentConfig
from excite_cli.config_file import load_problem
from excite_cli.errors import ExciteError
from excite_cli.plots.scene import write_scene


def test_a_scene_animates_every_mesh_at_its_placement_beside_the_world(tmp_path):
    robot = robot_of(load_problem(CONFIGS / "smoke.yaml"), collision=True)
    shapes = world_shapes(
        EnvironmentConfig.model_validate(
            {"shapes": [{"name": "ball", "type": "sphere", "centre": [0.5, 0, 0.3], "radius": 0.1}]}
        )
    )
    q = robot.home + np.linspace(0.0, 0.3, 4)[:, None] * np.ones(robot.n_joints)
    html = write_scene(tmp_path / "scene.html", robot, q, 10.0, shapes).read_text()
    payloads = re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html)
    commands = [umsgpack.unpackb(base64.b64decode(p)) for p in payloads]
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    names = [g.name for g in robot.collision_model.geometryObjects]
    assert {f"/meshcat/robot/visuals/{n}" for n in names} <= objects and "/meshcat/world/ball/a" in objects
    clips = {a["path"]: a["clip"] for c in commands if c["type"] == "set_animation" for a in c["animations"]}
    track = {t["name"]: t["keys"] for t in clips["/meshcat/robot/visuals/panda_hand_0"]["tracks"]}
    assert len(track[".position"]) == len(q)
    data, placements = robot.model.createData(), pin.GeometryData(robot.collision_model)
    for k, posture in enumerate(q):
        configuration = robot.q_reference.copy()
        configuration[robot.q_idx] = posture
        pin.framesForwardKinematics(robot.model, data, configuration)
        pin.updateGeometryPlacements(robot.model, data, robot.collision_model, placements)
        expected = placements.oMg[names.index("panda_hand_0")].translation
        np.testing.assert_allclose(track[".position"][k]["value"], expected, atol=1e-9)


def test_without_the_view_extra_a_scene_is_one_line_and_no_file(tmp_path, monkeypatch):
    """meshcat is the ``view`` extra: without it, writing a scene says which extra, and writes nothing."""
    import sys

    monkeypatch.setitem(sys.modules, "meshcat", None)  # import meshcat now raises ImportError
    robot = robot_of(load_problem(CONFIGS / "smoke.yaml"), collision=True)
    with pytest.raises(ExciteError, match=r"needs meshcat, which is not installed") as raised:
        write_scene(tmp_path / "scene.html", robot, robot.home[None, :], 10.0, [])
    assert "pip install 'excite[view]'" in raised.value.describe() and not (tmp_path / "scene.html").exists()
