"""The joints a starting config moves, from the robot's file alone: every revolute joint that follows no
other (``<mimic>``, an MJCF joint equality), except a gripper's. A gripper is found where the chain of
movable joints from the base branches (two child subtrees that each hold a movable joint, as two
fingers do), and by name (a joint named like a finger, a gripper or a hand, and the joints below it;
a mobile base's wheels too): its joints are held, so a Gen3 lite's finger does not become a seventh
arm joint. A robot that branches before its second joint (a humanoid's legs and arms) has no such
chain and keeps every revolute joint but those named so. A
continuous joint (a revolute joint without a range) moves within one turn each way of 0, given as
``robot.joint_ranges``, which the user narrows to what the cables allow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from excite_cli.dynamics.source import RobotSource
from excite_cli.errors import ExciteError

#: Words that name a gripper's or a hand's joints, and a mobile base's wheels.
GRIPPER_WORDS = ("finger", "gripper", "knuckle", "thumb", "hand", "wheel", "caster")
#: The range a continuous joint is drafted with [rad]: one turn each way of 0, rounded up.
CONTINUOUS_RANGE = [-3.1416, 3.1416]


@dataclass
class JointChoice:
    """The active joints, {held joint: value} [rad or m], {continuous joint: [lower, upper]} [rad], and
    {"section.field": why} for the config's comments."""

    active: list[str]
    held: dict[str, float]
    ranges: dict[str, list[float]] = field(default_factory=dict)
    assumptions: dict[str, str] = field(default_factory=dict)


def gripper_joints(model: pin.Model, movable: list[str]) -> list[str]:
    """The ``movable`` joints of ``model`` that belong to a gripper (module docstring), in model order."""
    ids = [model.getJointId(n) for n in movable]
    below = {j: [k for k in ids if j in model.supports[k].tolist() and k != j] for j in [0, *ids]}
    chain, joint = [], 0
    while True:
        branches = [k for k in ids if _first_movable_above(model, k, ids) == joint]
        if len(branches) != 1:
            break
        joint = branches[0]
        chain.append(joint)
    gripper = set(below[joint]) if len(branches) > 1 and len(chain) >= 2 else set()
    named = {k for k in ids if any(w in model.names[k].lower() for w in GRIPPER_WORDS)}
    for k in list(named):
        named.update(below[k])
    return [model.names[k] for k in ids if k in gripper | named]


def _first_movable_above(model: pin.Model, joint: int, ids: list[int]) -> int:
    """The nearest joint of ``ids`` that ``joint`` hangs from (0: none, the base)."""
    parent = model.parents[joint]
    while parent and parent not in ids:
        parent = model.parents[parent]
    return parent


def joint_choice(source: RobotSource, given: list[str] | None, model: pin.Model) -> JointChoice:
    """The active joints of a starting config and the others held (module docstring).

    Args:
        source: the URDF or MJCF; given: the active joints, or None (module docstring).
        model: pinocchio's model of it (:meth:`~excite_cli.dynamics.source.RobotSource.model`).

    Raises:
        ExciteError: a given joint that is not a 1-DoF joint of the file; no joint given and no
            revolute joint to move (naming the joints there are).
    """
    one_dof = [n for i, n in enumerate(model.names) if i > 0 and model.joints[i].nq == 1]
    mimics = set(source.couplings())
    path = source.path
    revolute = [n for n in one_dof if "R" in model.joints[model.getJointId(n)].shortname().replace("JointModel", "")]
    gripper = [] if given else gripper_joints(model, one_dof)
    bodies = {f.name for f in model.frames if f.type == pin.FrameType.BODY}
    unheld = [n for n in gripper if n in bodies]  # pinocchio cannot hold a joint named as a link
    gripper = [n for n in gripper if n not in unheld]
    active = list(given) if given else [n for n in revolute if n not in mimics and n not in gripper]
    if not active:
        others = {"prismatic": [n for n in one_dof if n not in revolute], "mimic": mimics, "gripper": gripper}
        said = "; ".join(f"{kind}: {', '.join(sorted(names))}" for kind, names in others.items() if names)
        raise ExciteError(
            "urdf",
            f"{path.name} has no revolute joint for excite to move ({said or 'its joints are all fixed'})",
            path.name,
            "a robot file with a revolute joint, or the 1-DoF joints to move named",
        )
    unknown = [n for n in active if n not in one_dof]
    if unknown:
        raise ExciteError(
            "joints", f"'{unknown[0]}' is not a 1-DoF joint of {path.name}", unknown[0], ", ".join(one_dof)
        )
    held = {}
    for name in (n for n in one_dof if n not in active):
        k = model.idx_qs[model.getJointId(name)]
        held[name] = float(np.clip(0.0, model.lowerPositionLimit[k], model.upperPositionLimit[k]))
    choice = JointChoice(active, held)
    choice.assumptions["robot.active_joints"] = (
        "the joints given" if given else "every revolute joint that follows no other (prismatic ones are held)"
    )
    if gripper:
        choice.assumptions["robot.active_joints"] += (
            f"; held as a gripper's, a hand's or a mobile base's: {', '.join(gripper)}"
        )
    if unheld:
        choice.assumptions["robot.active_joints"] += (
            f"; the gripper's {', '.join(unheld)} moves: a link has its name, and pinocchio cannot hold such a joint"
        )
    if held:
        choice.assumptions["robot.locked_joints"] = "the other joints, held at 0 (or their nearest limit)"
    for name in active:
        k = model.idx_qs[model.getJointId(name)]
        if math.isinf(model.lowerPositionLimit[k]) or math.isinf(model.upperPositionLimit[k]):
            choice.ranges[name] = list(CONTINUOUS_RANGE)
    if choice.ranges:
        choice.assumptions["robot.joint_ranges"] = (
            f"one turn each way of 0 for the joints without a range (continuous): {', '.join(choice.ranges)}; "
            "narrow it to what the cables allow"
        )
    return choice
