"""The joints a ``robot`` section moves and holds, checked against the robot's movable joints: known
names, 1-DoF active joints, each once, locked values inside the limits; a joint of more than one
degree of freedom held at the reference is said."""

from __future__ import annotations

import difflib
import warnings

import pinocchio as pin

from excite_cli.config import RobotConfig
from excite_cli.errors import ExciteError, ExciteWarning


def unknown_joint(field_name: str, name: str, known: list[str]) -> ExciteError:
    """The error of ``name`` at ``field_name``, not one of the ``known`` joints (the closest named)."""
    close = difflib.get_close_matches(name, known, n=1)
    hint = f"; did you mean '{close[0]}'?" if close else ""
    return ExciteError(field_name, f"'{name}' is not a joint of the robot{hint}")


def check_joints(cfg: RobotConfig, full: pin.Model) -> list[str]:
    """The movable joints of the full model, after checking the active and locked joints against them.

    Raises:
        ExciteError: an unknown joint, a joint that is not 1-DoF, a joint listed twice or both active
            and locked, a locked value outside the joint's limits.
    """
    movable = [n for j, n in enumerate(full.names) if j > 0 and full.joints[j].shortname() != "JointModelFreeFlyer"]
    for name in cfg.active_joints:
        if name not in movable:
            raise unknown_joint("robot.active_joints", name, movable)
        if full.joints[full.getJointId(name)].nq != 1:
            raise ExciteError("robot.active_joints", f"'{name}' is not a 1-DoF revolute or prismatic joint")
    if len(set(cfg.active_joints)) != len(cfg.active_joints):
        raise ExciteError("robot.active_joints", "a joint is listed twice")
    for name, value in cfg.locked_joints.items():
        if name not in movable:
            raise unknown_joint("robot.locked_joints", name, movable)
        if name in cfg.active_joints:
            raise ExciteError("robot.locked_joints", f"'{name}' is also an active joint")
        j = full.getJointId(name)
        lo, hi = full.lowerPositionLimit[full.idx_qs[j]], full.upperPositionLimit[full.idx_qs[j]]
        if full.joints[j].nv > 1:
            raise ExciteError(
                f"robot.locked_joints.{name}",
                f"'{name}' has {full.joints[j].nv} degrees of freedom: one value cannot hold it",
                value,
                "a 1-DoF joint (other joints not active are held at their reference)",
            )
        if full.joints[j].nq == 1 and not lo <= value <= hi:
            raise ExciteError(
                f"robot.locked_joints.{name}", f"{value} rad is outside the joint limits [{lo:g}, {hi:g}]"
            )
    held = [n for n in movable if full.joints[full.getJointId(n)].nv > 1 and n not in cfg.active_joints]
    if held:
        warnings.warn(
            f"robot.active_joints: {', '.join(repr(n) for n in held)} "
            f"{'is a joint' if len(held) == 1 else 'are joints'} of more than one degree of freedom (a ball "
            "joint): held at the reference (no rotation), as excite moves 1-DoF joints only",
            ExciteWarning,
            stacklevel=3,
        )
    return movable
