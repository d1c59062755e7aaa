"""The joints a robot section moves and holds, checked against the robot's movable joints."""

import pinocchio as pin
import pytest

from excite_cli.config import RobotConfig
from excite_cli.dynamics.active_joints import check_joints, unknown_joint
from excite_cli.errors import ExciteError


def _chain() -> pin.Model:
    """A revolute joint 'a', a spherical joint 'ball' and a revolute joint 'b' in a chain."""
    model = pin.Model()
    parent = 0
    for name, joint in (("a", pin.JointModelRZ()), ("ball", pin.JointModelSpherical()), ("b", pin.JointModelRY())):
        parent = model.addJoint(parent, joint, pin.SE3.Identity(), name)
    return model


def test_an_unknown_joint_is_named_with_the_closest_one():
    assert str(unknown_joint("robot.active_joints", "elbw", ["elbow", "wrist"])).endswith("did you mean 'elbow'?")


def test_the_joints_are_checked_and_a_held_ball_joint_is_said():
    model = _chain()
    with pytest.warns(match="'ball' is a joint of more than one degree of freedom"):
        assert check_joints(RobotConfig(urdf="x.urdf", active_joints=["a", "b"]), model) == ["a", "ball", "b"]
    for active, locked, said in (
        (["a", "a"], {}, "a joint is listed twice"),
        (["ball"], {}, "'ball' is not a 1-DoF"),
        (["a"], {"ball": 0.1}, "'ball' has 3 degrees of freedom"),
        (["a"], {"a": 0.1}, "'a' is also an active joint"),
    ):
        with pytest.raises(ExciteError, match=said):
            check_joints(RobotConfig(urdf="x.urdf", active_joints=active, locked_joints=locked), model)
