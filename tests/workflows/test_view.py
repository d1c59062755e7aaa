"""`excite view` (issue 19): the played motion as a 3D scene in one HTML file. The scene's commands
(meshcat's msgpack, base64 in the file) are decoded here: every mesh of the robot, the world
shapes, and an animation whose hand placements are pinocchio's forward kinematics of the exported
motion. Whether a browser shows the robot is `make view-check` (headless Chromium, see README)."""

import base64
import re

import numpy as np
import pinocchio as pin
import pytest
import umsgpack
import yaml
from conftest import CONFIGS, assert_refused, exported_motion, robot_of
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem

runner = CliRunner()
JOINTS = [f"panda_joint{k}" for k in range(1, 8)]


@pytest.fixture(scope="module")
def panda_result(tmp_path_factory):
    folder = tmp_path_factory.mktemp("view")
    config = yaml.safe_load((CONFIGS / "smoke.yaml").read_text())
    config["sequence"]["iterations"] = 1
    config["constraints"] = {
        "environment": {"shapes": [{"name": "table", "type": "half_space", "point": [0, 0, 0], "normal": [0, 0, 1]}]}
    }
    config["output"] = str(folder / "run.h5")
    (folder / "run.yaml").write_text(yaml.safe_dump(config))
    assert runner.invoke(app, ["optimize", str(folder / "run.yaml")]).exit_code == 0
    return folder


def _commands(html: str) -> list[dict]:
    payloads = re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html)
    return [umsgpack.unpackb(base64.b64decode(p)) for p in payloads]


def test_the_scene_plays_the_exported_motion_on_every_mesh_beside_the_table(panda_result):
    result = runner.invoke(app, ["view", str(panda_result / "run.h5"), "--rate", "10"])
    assert result.exit_code == 0, result.output
    commands = _commands((panda_result / "run_iteration1.html").read_text())
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    robot = robot_of(load_problem(panda_result / "run.yaml"), collision=True)
    meshes = [g.name for g in robot.collision_model.geometryObjects]
    assert {f"/meshcat/robot/visuals/{name}" for name in meshes} <= objects
    assert "/meshcat/world/table" in objects
    clips = {a["path"]: a["clip"] for c in commands if c["type"] == "set_animation" for a in c["animations"]}
    hand = {t["name"]: t["keys"] for t in clips["/meshcat/robot/visuals/panda_hand_0"]["tracks"]}
    assert (
        runner.invoke(
            app, ["export", str(panda_result / "run.h5"), "--rate", "10", "-o", str(panda_result / "p.csv")]
        ).exit_code
        == 0
    )
    q = exported_motion(panda_result / "p.csv", JOINTS)[0]
    assert len(hand[".position"]) == q.shape[0]
    data, placements = robot.model.createData(), pin.GeometryData(robot.collision_model)
    index = meshes.index("panda_hand_0")
    for k in range(0, q.shape[0], 7):
        configuration = robot.q_reference.copy()
        configuration[robot.q_idx] = q[k]
        pin.framesForwardKinematics(robot.model, data, configuration)
        pin.updateGeometryPlacements(robot.model, data, robot.collision_model, placements)
        assert np.allclose(hand[".position"][k]["value"], placements.oMg[index].translation, atol=1e-9)


@pytest.mark.parametrize("rate", ["0", "1000", "nan"])
def test_a_frame_rate_a_browser_cannot_play_is_refused(panda_result, tmp_path, rate):
    assert_refused(
        tmp_path, ["view", str(panda_result / "run.h5"), "--rate", rate, "-o", str(tmp_path / "v.html")], "--rate"
    )
