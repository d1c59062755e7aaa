"""The robot drawn as lines: each joint frame (moving, locked or fixed) joined to its parent joint
frame (``Robot.links``), from pinocchio's frame placements, and the capsules' segments, for
pictures of postures."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from excite_cli.collision.capsules import Capsule, segment_ends
from excite_cli.dynamics.kinematics import BatchKinematics
from excite_cli.dynamics.robot import Robot


def skeleton(robot: Robot, q: np.ndarray) -> np.ndarray:
    """(L, 2, 3) line segments [m], world frame, from each joint frame's parent joint frame to it, at
    the active joints' posture q (n,) [rad] (locked joints at their values, the base at identity)."""
    model = robot.model
    data = model.createData()
    qf = robot.q_reference.copy()
    qf[robot.q_idx] = q
    pin.framesForwardKinematics(model, data, qf)
    ids = {name: _joint_frame(model, name) for pair in robot.links for name in pair}
    return np.array([[data.oMf[ids[a]].translation, data.oMf[ids[b]].translation] for a, b in robot.links])


def capsule_segments(robot: Robot, capsules: list[Capsule], q: np.ndarray) -> np.ndarray:
    """(C, 2, 3) world end points [m] of every capsule's segment at the posture q (n,) [rad]."""
    if not capsules:
        return np.zeros((0, 2, 3))
    start, end, _, _ = segment_ends(BatchKinematics(robot), capsules, q[None, :])
    return np.stack([start[:, 0].T, end[:, 0].T], axis=1)


def _joint_frame(model: pin.Model, name: str) -> int:
    """The joint frame (moving, or held: fixed) called ``name``; a link may have the same name (so100's
    "gripper")."""
    for kind in (pin.FrameType.JOINT, pin.FrameType.FIXED_JOINT):
        if model.existFrame(name, kind):
            return model.getFrameId(name, kind)
    return model.getFrameId(name)
