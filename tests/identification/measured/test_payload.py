"""A known payload's parameters: its torque through the regressor equals pinocchio's RNEA of the
robot carrying it minus the robot's own."""

import numpy as np
import pinocchio as pin
import pytest
from conftest import CONFIGS, robot_of

from excite_cli.config_file import load_problem
from excite_cli.errors import ExciteError
from excite_cli.identification.data_config import PayloadConfig
from excite_cli.identification.measured.payload import payload_parameters


def test_payload_torque_through_the_regressor_is_the_rnea_of_the_robot_carrying_it():
    robot = robot_of(load_problem(CONFIGS / "smoke.yaml"))
    payload = PayloadConfig(
        mass=1.5, com=[0.02, -0.01, 0.08], inertia=[2e-3, 1e-4, 2.5e-3, 0.0, 2e-4, 1.5e-3], frame="panda_hand"
    )
    phi = payload_parameters(robot, payload, "data.runs[0].payload")
    carrying = pin.Model(robot.model)
    frame = carrying.frames[carrying.getFrameId("panda_hand")]
    xx, xy, yy, xz, yz, zz = payload.inertia
    body = pin.Inertia(1.5, np.array(payload.com), np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]))
    carrying.appendBodyToJoint(frame.parentJoint, body, frame.placement)
    for q, qd, qdd in zip(*robot.random_states(5, np.random.default_rng(1))):
        state = robot.state(q, qd, qdd)
        difference = pin.rnea(carrying, carrying.createData(), *state) - pin.rnea(
            robot.model, robot.model.createData(), *state
        )
        np.testing.assert_allclose(robot.regressor(q, qd, qdd) @ phi, difference[robot.row_idx], atol=1e-10)
    with pytest.raises(ExciteError, match="frame"):
        payload_parameters(robot, payload.model_copy(update={"frame": "tool0"}), "data.runs[0].payload")
