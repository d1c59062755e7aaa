"""The robot drawn as lines: each joint frame (moving, locked or fixed) joined to its parent joint
frame, from pinocchio's frame placements, and the capsules' segments, for pictures of postures."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from excite_cli.capsules import Capsule, capsule_placements
from excite_cli.robot import Robot

_JOINT_FRAMES = (pin.FrameType.JOINT, pin.FrameType.FIXED_JOINT)


def _links(model: pin.Model) -> list[tuple[int, int]]:
    """(parent frame, frame) index pairs of consecutive joint frames (moving or fixed)."""
    pairs = []
    for index, frame in enumerate(model.frames):
        if index == 0 or frame.type not in _JOINT_FRAMES:
            continue
        parent = frame.parentFrame
        while parent > 0 and model.frames[parent].type not in _JOINT_FRAMES:
            parent = model.frames[parent].parentFrame
        pairs.append((parent, index))
    return pairs


def skeleton(robot: Robot, q: np.ndarray) -> np.ndarray:
    """(L, 2, 3) line segments [m], world frame, from each joint frame's parent joint frame to it, at
    the active joints' posture q (n,) [rad] (locked joints at their values, the base at identity)."""
    model = robot.model
    data = model.createData()
    qf = robot.q_reference.copy()
    qf[robot.q_idx] = q
    pin.framesForwardKinematics(model, data, qf)
    return np.array([[data.oMf[a].translation, data.oMf[b].translation] for a, b in _links(model)])


def capsule_segments(robot: Robot, capsules: list[Capsule], q: np.ndarray) -> np.ndarray:
    """(C, 2, 3) world end points [m] of every capsule's segment at the posture q (n,) [rad]."""
    if not capsules:
        return np.zeros((0, 2, 3))
    rotations, centres = capsule_placements(robot, capsules, q[None, :])
    half = np.array([np.linalg.norm(c.end - c.start) / 2.0 for c in capsules])[:, None] * rotations[0, :, :, 2]
    return np.stack([centres[0] - half, centres[0] + half], axis=1)
