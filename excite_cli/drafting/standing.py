"""The standing problem a starting config drafts for a legged robot (a humanoid, a quadruped carrying an
arm): recognized from its files (:mod:`~excite_cli.drafting.stance`), its base floating but held still,
the arms moving, every other joint locked at the standing posture, the zero-moment point kept inside the
soles and the arms above the floor under them (the paper's setting, Section IV-B: HRP-4's arms moving while
it stands). Every number says where it came from."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np
import pinocchio as pin

from excite_cli.drafting.joints import JointChoice
from excite_cli.drafting.stance import Stance, find_stance
from excite_cli.dynamics.source import RobotSource
from excite_cli.errors import ExciteError


@dataclass(frozen=True)
class StandOptions:
    """What ``init`` is told of the robot's stance.

    Attributes:
        stand: True: a standing problem; False: a fixed base; None: standing where legs and an arm are found.
        srdf: the SRDF whose states are the named postures (None: the one beside the URDF).
        posture: the named state to stand in (None: :func:`~excite_cli.drafting.stance.named_posture`).
        soles: the links that touch the floor (None: found).
    """

    stand: Optional[bool] = None
    srdf: Optional[Path] = None
    posture: Optional[str] = None
    soles: Optional[list[str]] = None


#: Distance [m] the zero-moment point keeps from the soles' edges (the shipped G1 problem's), or two thirds of
#: the room from the polygon's centre to its nearest edge on small soles (iCub's 31 mm: with a third of it, 10 mm,
#: its centre of pressure came within 2.5 mm of the edge in MuJoCo on a joint PD and the feed-forward, 5.9 mm
#: with half, 16.3 mm with 20 mm).
ZMP_MARGIN = 0.02
#: Distance [m] the arms keep from the floor.
FLOOR_MARGIN = 0.02


def stance_for(
    source: RobotSource,
    model: pin.Model,
    options: StandOptions,
    collision: bool,
    joints: Optional[list[str]] = None,
) -> tuple[Optional[Stance], str]:
    """The stance a starting config drafts for the robot of ``source`` (its fixed-base ``model``), or None,
    and why, in words (for the config's comments).

    Args:
        options: ``stand`` True: a standing problem (refused where the robot's legs are not found); False: a
            fixed base (a legged robot on a stand, its free joint welded); None: standing where two or more
            chains reach the ground (legs) and an arm is found (or ``joints`` given); ``posture``, ``soles``:
            see :func:`~excite_cli.drafting.stance.find_stance`.
        collision: whether geometry may be read (without it no sole can be found: a fixed base).
        joints: the joints to move, if given.

    Raises:
        ExciteError: (``stand``) a standing problem asked for where no legs or soles are found, or without
            geometry; see :func:`~excite_cli.drafting.stance.find_stance`.
    """
    stand, free = options.stand, source.free_root()
    welded = f"; the file's free joint '{free}' welded" if free else ""
    if stand is False:
        return None, "a fixed base, as asked" + welded
    if not collision:
        if stand:
            raise ExciteError("stand", "a standing robot needs its soles' collision geometry, which is not read")
        return None, "a fixed base: no collision geometry read, so no soles to stand on" + welded
    stance = find_stance(source, model, source.geometry(model), options.posture, options.soles)
    if stance is None:
        if stand or free:
            raise ExciteError(
                "stand",
                f"{source.path.name} "
                + (f"declares a floating base (free joint '{free}') but " if free else "")
                + "has fewer than two chains of joints that reach the ground (legs)",
                None,
                "the links that touch the floor named (soles), or a fixed base (no stand)",
            )
        return None, "a fixed base: fewer than two chains of joints reach the ground (no legs)"
    if not stance.arms and not joints and not stand:
        return None, f"a fixed base (on a stand): {len(stance.legs)} legs but no arm to move while standing" + welded
    how = f"the file's free joint '{free}'" if free else f"its root carries {len(stance.legs)} legs"
    return stance, (
        f"a standing robot: {how}, standing on {', '.join(stance.soles)}; the base is held still, the legs "
        "and the rest locked at the standing posture"
    )


def standing_choice(stance: Stance, given: Optional[list[str]], model: pin.Model) -> JointChoice:
    """The active joints of a standing problem (``given``, else the arms') and every other 1-DoF joint
    held at the standing posture [rad or m], rounded to 0.1 mrad.

    Raises:
        ExciteError: (``joints``) no arm found and no joint given; a given joint that is not a 1-DoF joint.
    """
    arms = [j for arm in stance.arms for j in arm]
    active = list(given) if given else arms
    if not active:
        raise ExciteError("joints", "no arm found to move while the robot stands", None, "the joints to move named")
    unknown = [n for n in active if n not in stance.posture]
    if unknown:
        raise ExciteError("joints", f"'{unknown[0]}' is not a 1-DoF joint", unknown[0], ", ".join(stance.posture))
    held = {n: round(v, 4) + 0.0 for n, v in stance.posture.items() if n not in active}
    choice = JointChoice(active, held)
    choice.assumptions["robot.active_joints"] = (
        "the joints given"
        if given
        else "the arms: " + "; ".join(f"{arm[0]} … {arm[-1]} ({len(arm)} joints)" for arm in stance.arms)
    )
    choice.assumptions["robot.locked_joints"] = (
        "every other joint at the standing posture: " + stance.why["robot.locked_joints"]
    )
    return choice


def standing_constraints(stance: Stance, capsule_margin: float) -> dict:
    """The constraints section of a standing problem: the zero-moment point inside the soles less
    :data:`ZMP_MARGIN`, self-collision between fitted capsules (``capsule_margin`` [m]) and the floor under
    the soles, :data:`FLOOR_MARGIN` from the capsules."""
    floor = round(stance.floor, 4) + 0.0
    return {
        "zmp": {"support_links": list(stance.soles), "margin": zmp_margin(stance)},
        "self_collision": {"capsules": "auto", "margin": capsule_margin, "exclude_pairs": []},
        "environment": {
            "shapes": [
                {
                    "name": "floor",
                    "type": "half_space",
                    "point": [0.0, 0.0, floor],
                    "normal": [0.0, 0.0, 1.0],
                    "margin": FLOOR_MARGIN,
                }
            ]
        },
    }


def zmp_margin(stance: Stance) -> float:
    """:data:`ZMP_MARGIN`, or two thirds of the soles' room (``Stance.room``) where that is less [m], to the mm."""
    return min(ZMP_MARGIN, float(np.floor(1000 * stance.room * 2 / 3)) / 1000)


def standing_assumptions(stance: Stance) -> dict[str, str]:
    """{"section.field": where it came from} of a standing problem's constraints, for the config's comments."""
    return {
        "constraints.zmp": (
            f"the zero-moment point {1000 * zmp_margin(stance):g} mm inside the soles' polygon (its centre is "
            f"{1000 * stance.room:.0f} mm from the nearest edge): the lowest collision points of "
            f"{', '.join(stance.soles)} at the standing posture (those within 1 mm of the lowest)"
        ),
        "constraints.environment": (
            f"the floor under the soles, z = {stance.floor:.4f} m (forward kinematics at the standing posture, "
            f"the base at the identity), the arms {1000 * FLOOR_MARGIN:g} mm above it"
        ),
    }
