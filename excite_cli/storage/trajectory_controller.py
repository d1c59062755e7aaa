"""What ros2_control's joint_trajectory_controller accepts: its checks of an incoming
``trajectory_msgs/msg/JointTrajectory``, so that an exported trajectory reaches the robot.

Written from the controller's documented behaviour and its source (ros2_controllers,
``joint_trajectory_controller/src/joint_trajectory_controller.cpp``, ``validate_trajectory_msg`` and
``validate_trajectory_point_field``, the same on the Humble and Jazzy branches; user documentation,
"Hardware interface types"). A message the controller refuses is one ERROR line in the controller's
log while ``ros2 bag play`` ends normally and the robot does not move, so excite checks before it
writes:

- the joint names are not empty and none repeats;
- there is at least one point;
- ``time_from_start`` strictly increases from point to point;
- every point has one position per joint, and velocities and accelerations either empty or one per
  joint;
- the last point's velocities are zero (|v| ≤ float32's epsilon, unless the controller's
  ``allow_nonzero_velocity_at_trajectory_end`` is set, which excite does not assume);
- ``effort`` is empty: the controller refuses any point with effort ("Trajectories with effort fields
  are currently not supported.") on Humble for every command interface, and on Jazzy unless the
  joints are effort-controlled, which ros2_controllers accepts from 4.22 on. excite writes effort
  only when asked (``effort``), for such a controller.

Every value is also finite (a NaN would reach the hardware interface).
"""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np

#: The largest velocity the controller counts as zero at the trajectory's end (float32's epsilon).
AT_REST = float(np.finfo(np.float32).eps)


def time_from_start_ns(time_s: np.ndarray) -> np.ndarray:
    """(S,) int64 [ns]: each point's ``time_from_start`` as the messages carry it, from ``time_s`` (S,)
    [s] rounded to the nanosecond (the writers and :func:`controller_refusals` use the same)."""
    return np.round(np.asarray(time_s) * 1e9).astype(np.int64)


def controller_refusals(
    joint_names: Sequence[str],
    time_ns: np.ndarray,
    positions: np.ndarray,
    velocities: Optional[np.ndarray],
    accelerations: Optional[np.ndarray],
    effort: Optional[np.ndarray],
    effort_interface: bool = False,
) -> list[str]:
    """The reasons the joint_trajectory_controller (module docstring) would refuse a trajectory, in
    its words; empty when it accepts it.

    Args:
        joint_names: (n,) the message's joint names.
        time_ns: (S,) each point's ``time_from_start`` [ns].
        positions: (S, n) [rad]; velocities, accelerations: (S, n) [rad/s, rad/s²] or None (empty).
        effort: (S, n) [Nm] or None (empty fields).
        effort_interface: the controller's joints are effort-controlled (Jazzy, ros2_controllers ≥ 4.22).
    """
    n, refusals = len(joint_names), []
    if n == 0:
        refusals.append("Empty joint names on incoming trajectory.")
    if len(set(joint_names)) != n:
        refusals.append("a joint name is given twice")
    if len(time_ns) == 0:
        return refusals + ["Empty trajectory received."]
    steps = np.flatnonzero(np.diff(np.asarray(time_ns)) <= 0)
    if steps.size:
        refusals.append(f"Time between points {steps[0]} and {steps[0] + 1} is not strictly increasing")
    for name, field, optional in (
        ("positions", positions, False),
        ("velocities", velocities, True),
        ("accelerations", accelerations, True),
        ("effort", effort if effort_interface else None, True),
    ):
        if field is None:
            if not optional:
                refusals.append(f"no {name}")
            continue
        if np.shape(field) != (len(time_ns), n):
            refusals.append(f"Mismatch between joint_names size ({n}) and {name} {np.shape(field)}")
        elif not np.all(np.isfinite(field)):
            refusals.append(f"{name} holds NaN or infinite values")
    if velocities is not None and np.shape(velocities)[-1:] == (n,) and np.any(np.abs(velocities[-1]) > AT_REST):
        j = int(np.argmax(np.abs(velocities[-1])))
        refusals.append(f"Velocity of last trajectory point of joint {joint_names[j]} is not zero")
    if effort is not None and not effort_interface:
        refusals.append("Trajectories with effort fields are currently not supported.")
    return refusals
