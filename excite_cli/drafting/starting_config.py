"""A starting ``optimize`` config for a robot excite has never seen, from its URDF alone: which joints
move, limits with a margin, capsules fitted to the collision meshes with the pairs that overlap at
every posture left out, a mounting plane under the base, torque limits from the URDF's effort, and a
home posture every constraint accepts (:mod:`~excite_cli.drafting.home_posture`). Every choice is
recorded as an assumption, in words, for the written file's comments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from excite_cli.config_file import drafted_problem
from excite_cli.design.excitation import Excitation
from excite_cli.design.noise import typical_torques
from excite_cli.design.resolve import build_excitation
from excite_cli.drafting.home_posture import home_posture
from excite_cli.drafting.joints import joint_choice
from excite_cli.drafting.noise_source import draft_noise
from excite_cli.drafting.stance import Stance
from excite_cli.drafting.standing import (
    StandOptions,
    stance_for,
    standing_assumptions,
    standing_choice,
    standing_constraints,
)
from excite_cli.dynamics.source import RobotSource, apply_joint_ranges
from excite_cli.errors import ExciteError

#: Random postures the capsule overlaps and the home posture are searched over.
POSTURES = 300
#: Joint velocity limit as a fraction of the URDF's; acceleration limit per rad/s of it [1/s].
VELOCITY_FRACTION, ACCELERATION_PER_VELOCITY = 0.5, 3.0
#: A standing robot's velocity [rad/s] and acceleration [rad/s²] limits at most: the shipped G1 problem's.
STANDING_LIMITS = (2.0, 8.0)
#: Margins [m]: between capsules, and from the mounting plane.
CAPSULE_MARGIN, PLANE_MARGIN = 0.01, 0.02
#: A capsule pair never farther apart than this over the random postures [m] is left out: two
#: neighbouring links whose fitted capsules touch wherever the joints are (the links need not).
NEVER_APART = 2 * CAPSULE_MARGIN


@dataclass
class StartingConfig:
    """A drafted config (the YAML's mapping, section by section) and the assumptions behind it:
    {"section.field": why} for the comments, the excluded pairs and ignored links with reasons, and
    what must be fixed before it runs ("" when nothing)."""

    config: dict
    assumptions: dict[str, str] = field(default_factory=dict)
    excluded: list[tuple[str, str, str]] = field(default_factory=list)
    ignored: list[tuple[str, str]] = field(default_factory=list)
    problem: str = ""


def _limits(model: pin.Model, active: list[str], draft: StartingConfig, standing: bool = False) -> dict:
    """Position margin, velocity and acceleration limits per joint (a ``standing`` robot's at most
    :data:`STANDING_LIMITS`), torque limits where the URDF (its ``model``) has them.

    Raises:
        ExciteError: an active joint whose URDF limits leave no range.
    """
    ids = [model.getJointId(n) for n in active]
    velocity = {
        n: round(VELOCITY_FRACTION * float(model.velocityLimit[model.idx_vs[i]]), 3) for n, i in zip(active, ids)
    }
    missing = [n for n, v in velocity.items() if not 0 < v < math.inf]
    for name in missing:
        velocity[name] = 1.0
    if standing:
        velocity = {n: min(v, STANDING_LIMITS[0]) for n, v in velocity.items()}
    ranges = [model.upperPositionLimit[model.idx_qs[i]] - model.lowerPositionLimit[model.idx_qs[i]] for i in ids]
    still = [n for n, r in zip(active, ranges) if not r > 0]
    if still:
        raise ExciteError(
            "urdf",
            f"the URDF gives {', '.join(still)} no position range (lower = upper): excite moves joints inside "
            "their URDF limits",
            still[0],
            "a <limit lower upper> on each joint to move, or other joints named (the joints option)",
        )
    limits = {
        "position_margin": round(min(0.1, 0.1 * float(min(ranges))), 3),
        "velocity": velocity,
        "acceleration": {n: round(ACCELERATION_PER_VELOCITY * v, 3) for n, v in velocity.items()},
    }
    if standing:
        limits["acceleration"] = {n: min(a, STANDING_LIMITS[1]) for n, a in limits["acceleration"].items()}
    draft.assumptions["limits.position_margin"] = "0.1 rad inside every limit of the file (less for a short range)"
    draft.assumptions["limits.velocity"] = f"{VELOCITY_FRACTION:g} × the file's velocity limit" + (
        f" (1 rad/s where it has none: {', '.join(missing)})" if missing else ""
    )
    draft.assumptions["limits.acceleration"] = f"{ACCELERATION_PER_VELOCITY:g} × the velocity limit per second"
    if standing:
        draft.assumptions["limits.velocity"] += f", at most {STANDING_LIMITS[0]:g} rad/s"
        draft.assumptions["limits.acceleration"] += (
            f", at most {STANDING_LIMITS[1]:g} rad/s²: a standing robot's arms as the shipped G1 problem moves them "
            "(a lab's stance sways under faster arms: the G1 drafted at half its URDF's 22-37 rad/s put the centre "
            "of pressure 13 mm from its soles' edge in MuJoCo, iCub at its URDF's 50 rad/s 2 mm)"
        )
    data = model.createData()
    pin.computeSubtreeMasses(model, data)
    idle = [n for n, i in zip(active, ids) if not data.mass[i] > 0.0]
    if idle:
        draft.assumptions["limits.torque"] = f"none: {', '.join(idle)} move(s) no mass in the file (no <inertial>?)"
    elif all(0 < model.effortLimit[model.idx_vs[i]] < math.inf for i in ids):
        limits["torque"] = "urdf"
        draft.assumptions["limits.torque"] = "the file's effort limits (an MJCF's: its actuators' force ranges × gear)"
    else:
        unbounded = [n for n, i in zip(active, ids) if not 0 < model.effortLimit[model.idx_vs[i]] < math.inf]
        draft.assumptions["limits.torque"] = f"none: the file bounds no torque of {', '.join(unbounded)} (unchecked)"
    return limits


def _base_floor(model: pin.Model, source: RobotSource) -> float:
    """Height [m] of the lowest point of the root link's collision geometry (0 without any), from the
    robot's ``source`` and its ``model``."""
    geometry = source.geometry(model)
    data, gdata = model.createData(), pin.GeometryData(geometry)
    pin.updateGeometryPlacements(model, data, geometry, gdata, pin.neutral(model))
    lowest = 0.0
    for k, g in enumerate(geometry.geometryObjects):
        if g.parentJoint == 0 and hasattr(g.geometry, "vertices"):
            placement = gdata.oMg[k]
            points = np.asarray(g.geometry.vertices()) @ placement.rotation.T  # at its URDF scale already
            lowest = min(lowest, float((points + placement.translation)[:, 2].min()))
    return lowest


def _random_postures(excitation: Excitation, rng: np.random.Generator) -> np.ndarray:
    """(POSTURES, n) postures drawn uniformly inside the position bounds (their margin included)."""
    centre, half = excitation.limits.centre[0], 0.95 * excitation.limits.half[0]
    return centre + half * rng.uniform(-1.0, 1.0, (POSTURES, centre.size))


def _always_overlapping(excitation: Excitation, Q: np.ndarray, draft: StartingConfig) -> None:
    """Capsule pairs never farther apart than :data:`NEVER_APART` over the postures Q, or that no motion
    brings within their margin: excluded (as link pairs), with why; links within a world shape's margin at
    every posture: ignored by the world constraint, with why."""
    for c in excitation.constraints:
        for pair, distance in c.never_apart(Q, NEVER_APART):
            if pair not in [(x, y) for x, y, _ in draft.excluded]:
                farthest = distance * 100
                why = (
                    f"never more than {farthest:.1f} cm apart at {len(Q)} random postures"
                    if farthest >= 0
                    else f"overlapping by at least {-farthest:.1f} cm at all {len(Q)} random postures"
                ) + ": the capsules of neighbouring links, which touch at every posture"
                draft.excluded.append((*pair, why))
        for pair, gap in c.out_of_reach():
            if pair not in [(x, y) for x, y, _ in draft.excluded]:
                draft.excluded.append(
                    (*pair, f"out of reach: never closer than {100 * gap:.1f} cm, whatever the joints do")
                )
        for link, margin in c.always_within(Q):
            if link not in [x for x, _ in draft.ignored]:
                draft.ignored.append((link, f"within {margin:g} m of the plane under it at all postures"))


#: The trajectory, optimizer and sequence a starting config gets: the shipped lab arms' (10 s, 5 harmonics),
#: the constraint grid sampling the highest harmonic 40 times per period, as the shipped G1 problem's does
#: (10 harmonics of π/4 rad/s on 0.02 s): 0.05 s. The optimizer's sizes are fitted to the budget by ``init``
#: (:func:`~excite_cli.search.run_time.sizes_within`), up to 400 solver iterations per restart (a restart
#: stops where it converges; on the UR10 a kept restart stuck at KKT 0.12 after 200 converged at 292).
HARMONICS, BASE_FREQUENCY, SAMPLES_PER_PERIOD = 5, 2 * math.pi / 10, 40
TRAJECTORY = {
    "harmonics": HARMONICS,
    "base_frequency": BASE_FREQUENCY,
    "cost_samples": 50,
    "cost_period": 0.2,
    "constraint_period": math.floor(100 * 2 * math.pi / (HARMONICS * BASE_FREQUENCY) / SAMPLES_PER_PERIOD) / 100,
    "boundary": "rest",
}
OPTIMIZER = {"max_iterations": 400, "restarts": 4, "starts": 16, "screen_iterations": 40}


def _choose_joints(
    source: RobotSource, model: pin.Model, joints: list[str] | None, stance: Stance | None, draft: StartingConfig
) -> None:
    """The robot section's joints and ranges in ``draft``: a standing robot's
    (:func:`~excite_cli.drafting.standing.standing_choice`), else
    :func:`~excite_cli.drafting.joints.joint_choice`'s; ``model`` given those ranges."""
    choice = standing_choice(stance, joints, model) if stance else joint_choice(source, joints, model)
    apply_joint_ranges(model, {n: tuple(r) for n, r in choice.ranges.items()}, source.path.name)
    if stance:
        draft.config["robot"]["floating_base"] = True
    draft.config["robot"].update(active_joints=choice.active, locked_joints=choice.held)
    if choice.ranges:
        draft.config["robot"]["joint_ranges"] = choice.ranges
    draft.config["robot"]["home_posture"] = {}
    draft.assumptions.update(choice.assumptions)


def _constraints(model: pin.Model, source: RobotSource, stance: Stance | None, draft: StartingConfig) -> None:
    """A standing robot's constraints (:func:`~excite_cli.drafting.standing.standing_constraints`), else
    capsules and a mounting plane under the base, in ``draft``."""
    if stance:
        draft.config["constraints"] = standing_constraints(stance, CAPSULE_MARGIN)
        draft.assumptions.update(standing_assumptions(stance))
        return
    floor = round(_base_floor(model, source), 4) + 0.0  # no -0
    plane = {"name": "mounting_plane", "type": "half_space", "point": [0.0, 0.0, floor], "normal": [0.0, 0.0, 1.0]}
    draft.config["constraints"] = {
        "self_collision": {"capsules": "auto", "margin": CAPSULE_MARGIN, "exclude_pairs": []},
        "environment": {"shapes": [{**plane, "margin": PLANE_MARGIN}]},
    }
    draft.assumptions["constraints.environment"] = (
        f"a plane under the base (z = {floor:g} m, the base's lowest collision point): the table top or floor"
    )


def draft_config(
    robot: dict,
    source: RobotSource,
    joints: list[str] | None,
    target: Path,
    collision: bool = True,
    options: StandOptions = StandOptions(),
    torque_from: str = "unknown",
) -> StartingConfig:
    """A starting config for the URDF or MJCF of ``robot`` (the section's ``urdf`` and ``source``), to be
    written to ``target``: a standing problem for a legged robot
    (:func:`~excite_cli.drafting.standing.stance_for`), else a fixed base. When no home posture holds, the
    best one found is written and ``StartingConfig.problem`` says what binds there (the file's comments too).

    Args:
        robot: {"urdf": ..., "source": ...} as the config will say them.
        source: the robot's file (and where its meshes are).
        joints: the active joints, or None (the arms of a standing robot, else see
            :func:`~excite_cli.drafting.joints.joint_choice`).
        collision: fit capsules to the collision meshes and draft a mounting plane or the floor; False:
            neither (no meshes are read, and no standing problem drafted).
        options: what the user said of the stance (:func:`~excite_cli.drafting.standing.stance_for`).
        torque_from: where the lab's torques come from, one of
            :data:`~excite_cli.drafting.noise_source.SOURCES`: the ``noise`` section drafted for it.

    Raises:
        ExciteError: an unknown joint; a mesh that cannot be read; see
            :func:`~excite_cli.drafting.standing.stance_for`.
    """
    draft = StartingConfig({"robot": dict(robot)})
    model = source.model()
    stance, draft.assumptions["robot.floating_base"] = stance_for(source, model, options, collision, joints)
    _choose_joints(source, model, joints, stance, draft)
    active = draft.config["robot"]["active_joints"]
    draft.config["trajectory"] = dict(TRAJECTORY)
    draft.config["limits"] = _limits(model, active, draft, stance is not None)
    if collision:
        _constraints(model, source, stance, draft)
    draft.config["optimizer"] = dict(OPTIMIZER)
    draft.config["sequence"] = {"iterations": 3}
    draft.config["output"] = f"results/{source.path.stem}.h5"
    excitation = build_excitation(drafted_problem(draft.config, target), check_home=False)
    if not any(len(c.capsules) for c in excitation.constraints):
        for section in ("self_collision", "environment"):
            draft.config.get("constraints", {}).pop(section, None)
        if not draft.config.get("constraints"):
            draft.config.pop("constraints", None)
        draft.assumptions.pop("constraints.environment", None)
        which = "constraints.self_collision" if "constraints" in draft.config else "constraints"
        draft.assumptions[which] = (
            "none: "
            + ("the file has no collision geometry on a moving link" if collision else "collision geometry not read")
            + " (give capsules in constraints.self_collision)"
        )
    Q = _random_postures(excitation, np.random.default_rng(0))
    _always_overlapping(excitation, Q, draft)
    capsules = draft.config.get("constraints", {}).get("self_collision")
    if capsules:
        capsules["exclude_pairs"] = [[a, b] for a, b, _ in draft.excluded]
    if draft.ignored:
        draft.config["constraints"]["environment"]["ignore_links"] = [link for link, _ in draft.ignored]
    # the same robot: its base parameters need not be computed again
    excitation = build_excitation(drafted_problem(draft.config, target), excitation.base, check_home=False)
    first = np.array([stance.posture[n] for n in active]) if stance else None
    home, why, found = home_posture(excitation, Q, np.random.default_rng(1), first)
    draft.config["robot"]["home_posture"] = {n: round(float(q), 4) for n, q in zip(active, home)}
    draft.assumptions["robot.home_posture"] = f"searched: {why}" if found else f"FIX FIRST: {why}"
    draft.problem = "" if found else why
    typical = np.zeros(len(active))
    if torque_from != "unknown":  # the typical torques about the home posture just found
        excitation = build_excitation(drafted_problem(draft.config, target), excitation.base, check_home=False)
        typical = typical_torques(excitation)
    noise, draft.assumptions["noise"] = draft_noise(torque_from, active, typical)
    if noise:
        output = draft.config.pop("output")
        draft.config.update(noise=noise, output=output)
    return draft
