"""A known payload carried during a run (a tool, a calibrated mass): its inertial parameters placed on
the body that carries it, so that its torque can be taken out of the measured torque before the fit
(the identified model is then the robot's own)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.identification.data_config import PayloadConfig


def payload_parameters(robot: Robot, payload: PayloadConfig, field_name: str) -> np.ndarray:
    """(p,) standard parameters [kg, kg·m, kg·m²] of the payload on the body of its frame, zero
    elsewhere: τ_payload = Y(q, q̇, q̈) · this (Eq. 1).

    Args:
        payload: mass [kg], centre of mass [m] and inertia about it [kg·m²] in ``payload.frame``
            (default: the link carried by the last active joint).
        field_name: the config field, for messages.

    Raises:
        ExciteError: a frame the robot's model does not have.
    """
    frame = payload.frame or robot.body_names[-1]
    if not robot.model.existFrame(frame):
        raise ExciteError(
            f"{field_name}.frame", f"'{frame}' is not a frame of the robot's model", frame, "a frame of the URDF"
        )
    kind = pin.FrameType.BODY if robot.model.existFrame(frame, pin.FrameType.BODY) else None  # a joint may share it
    placement = robot.model.frames[robot.model.getFrameId(frame, kind) if kind else robot.model.getFrameId(frame)]
    xx, xy, yy, xz, yz, zz = payload.inertia
    inertia = pin.Inertia(
        payload.mass, np.asarray(payload.com, dtype=float), np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    )
    out = np.zeros(robot.n_parameters)
    body = placement.parentJoint - 1
    out[10 * body : 10 * body + 10] = placement.placement.act(inertia).toDynamicParameters()
    return out
