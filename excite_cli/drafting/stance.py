"""A standing robot from its own files (``excite init`` on a humanoid, or on a legged robot carrying an
arm): which chains are legs and which are arms, the soles, the posture it stands in and the floor.

The robot's movable joints (a gripper's and a hand's left out, :func:`~excite_cli.drafting.joints.gripper_joints`)
form chains, each from a leaf joint up to the joint where the body branches (or the base):

- **legs**: the chains whose links come within :data:`FOOT_HEIGHT` of the robot's lowest collision point
  at the standing posture; two or more make a standing robot;
- **soles**: on each leg, the links whose collision geometry reaches within :data:`SOLE_HEIGHT` of the
  leg's lowest point (the bottoms of a foot's spheres or boxes, an ankle mesh's lowest vertices), or the
  links given;
- **arms**: the other chains of :data:`ARM_JOINTS` or more revolute joints, but a head's (a joint named
  like a neck, a head or an eye);
- **posture**: a state the robot's files name (an SRDF's ``group_state``, an MJCF's keyframe): the one
  asked for, else ``half_sitting``, else the first whose name begins with ``standing``, else ``home``;
  else searched (:func:`~excite_cli.drafting.posture_search.searched_posture`): the soles as at the zero
  posture, a little higher (knees slightly bent), the centre of mass over the soles' centre;
- **floor**: the height of the soles' lowest point at that posture, the base at the identity (the
  frame excite holds the base in).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from scipy.spatial import QhullError

from excite_cli.collision.geometry import shape_points
from excite_cli.constraints.support import SupportPolygon
from excite_cli.constraints.zmp import CONTACT_HEIGHT
from excite_cli.drafting.joints import gripper_joints
from excite_cli.drafting.posture_search import SOLE_HEIGHT, levelled_posture, placed_points, searched_posture
from excite_cli.dynamics.source import RobotSource
from excite_cli.errors import ExciteError

#: A chain whose links come this close to the robot's lowest point [m] stands on the ground: a leg.
FOOT_HEIGHT = 0.02
#: Revolute joints an arm has at least (a head's chain has 2-4, and is named so).
ARM_JOINTS = 3
#: Words that name a head's joints.
HEAD_WORDS = ("head", "neck", "eye", "gaze", "camera", "lidar")
#: State names a standing posture is taken from, in this order (then a name beginning with the last).
STATE_NAMES = ("half_sitting", "home", "standing")


@dataclass
class Stance:
    """How a robot stands, from its files.

    Attributes:
        posture: {joint: value [rad or m]} of every movable 1-DoF joint at the standing posture.
        legs: the leg chains (joint names, from the body to the foot).
        arms: the arm chains (joint names, from the body to the hand).
        soles: the links that touch the floor.
        floor: the floor's height [m], the base at the identity.
        room: the distance [m] from the centre of the soles' polygon to its nearest edge (the polygon of
            their points within ``CONTACT_HEIGHT`` of the floor, as the zero-moment point's).
        why: {"section.field": where the numbers came from, in words}.
    """

    posture: dict[str, float]
    legs: list[list[str]]
    arms: list[list[str]]
    soles: list[str]
    floor: float
    room: float
    why: dict[str, str] = field(default_factory=dict)


def chains(model: pin.Model) -> list[list[int]]:
    """The chains of movable 1-DoF joints of ``model`` (module docstring), a gripper's left out: each from
    the joint below a branching joint (or the base) to a leaf, as joint ids, in model order of their leaves."""
    one_dof = [n for i, n in enumerate(model.names) if i > 0 and model.joints[i].nq == 1]
    skipped = set(gripper_joints(model, one_dof))
    ids = [model.getJointId(n) for n in one_dof if n not in skipped]
    above = {}
    for j in ids:
        parent = model.parents[j]
        while parent and parent not in ids:
            parent = model.parents[parent]
        above[j] = parent
    children = {j: [k for k in ids if above[k] == j] for j in [0, *ids]}
    found = []
    for leaf in (j for j in ids if not children[j]):
        chain = [leaf]
        while above[chain[0]] and len(children[above[chain[0]]]) == 1:
            chain.insert(0, above[chain[0]])
        found.append(chain)
    return found


def link_points(model: pin.Model, geometry: pin.GeometryModel) -> dict[str, tuple[int, np.ndarray]]:
    """{link: (its joint's id, (k, 3) collision-geometry points [m] in that joint's frame)} of every link
    with collision geometry."""
    points: dict[str, tuple[int, list]] = {}
    for obj in geometry.geometryObjects:
        local = shape_points(obj.geometry) @ obj.placement.rotation.T + obj.placement.translation
        points.setdefault(model.frames[obj.parentFrame].name, (obj.parentJoint, []))[1].append(local)
    return {link: (joint, np.vstack(parts)) for link, (joint, parts) in points.items()}


def posture_vector(model: pin.Model, values: dict[str, float]) -> np.ndarray:
    """(nq,) the zero posture with the 1-DoF joints ``values`` names set, clipped into their limits."""
    q = pin.neutral(model)
    for name, value in values.items():
        if model.existJointName(name) and model.joints[model.getJointId(name)].nq == 1:
            k = model.idx_qs[model.getJointId(name)]
            q[k] = np.clip(value, model.lowerPositionLimit[k], model.upperPositionLimit[k])
    return q


def find_legs(
    model: pin.Model, points: dict[str, tuple[int, np.ndarray]], q: np.ndarray
) -> tuple[list[list[int]], list[list[int]]]:
    """(legs, other chains) of ``model`` at the posture ``q``: the chains (:func:`chains`) whose links come
    within :data:`FOOT_HEIGHT` of the lowest collision point, and the rest."""
    placed = placed_points(model, q, points)
    lowest = min(p[:, 2].min() for p in placed.values())
    legs, others = [], []
    for chain in chains(model):
        carried = [p for link, p in placed.items() if points[link][0] in _subtree(model, chain[-1]) | set(chain)]
        low = min((p[:, 2].min() for p in carried), default=np.inf)
        (legs if low <= lowest + FOOT_HEIGHT else others).append(chain)
    return legs, others


def _subtree(model: pin.Model, joint: int) -> set[int]:
    """The joints ``joint`` carries, itself included."""
    return {k for k in range(1, model.njoints) if joint in model.supports[k].tolist()}


def sole_links(model: pin.Model, points: dict, q: np.ndarray, legs: list[list[int]]) -> list[str]:
    """The links of each leg whose points at ``q`` come within :data:`SOLE_HEIGHT` of the leg's lowest."""
    placed = placed_points(model, q, points)
    soles = []
    for leg in legs:
        carried = {link: p for link, p in placed.items() if points[link][0] in _subtree(model, leg[-1]) | set(leg)}
        lowest = min(p[:, 2].min() for p in carried.values())
        soles += [link for link, p in carried.items() if p[:, 2].min() <= lowest + SOLE_HEIGHT]
    return soles


def arm_chains(model: pin.Model, others: list[list[int]]) -> list[list[int]]:
    """The chains of ``others`` that are arms (module docstring)."""
    revolute = {j for j in range(1, model.njoints) if "R" in model.joints[j].shortname().replace("JointModel", "")}
    head = [c for c in others if any(w in model.names[j].lower() for j in c for w in HEAD_WORDS)]
    return [c for c in others if c not in head and sum(j in revolute for j in c) >= ARM_JOINTS]


def named_posture(states: dict[str, dict[str, float]], asked: str | None) -> str | None:
    """The state of ``states`` a standing posture is taken from: ``asked``, else (module docstring); None
    when there is none.

    Raises:
        ExciteError: (``posture``) ``asked`` is not a state of the files.
    """
    if asked is not None:
        if asked not in states:
            raise ExciteError(
                "posture", f"'{asked}' is not a state the robot's files name", asked, ", ".join(states) or "none named"
            )
        return asked
    for name in STATE_NAMES[:-1]:
        if name in states:
            return name
    return next((n for n in states if n.startswith(STATE_NAMES[-1])), None)


def find_stance(
    source: RobotSource, model: pin.Model, geometry: pin.GeometryModel, asked: str | None, soles: list[str] | None
) -> Stance | None:
    """How the robot of ``source`` stands (module docstring), or None where fewer than two chains reach the
    ground (not a legged robot) or it has no collision geometry.

    Args:
        model, geometry: the file's model with a fixed base and its collision geometry.
        asked: the named state to stand in, or None (module docstring).
        soles: the links that touch the floor, or None: found.

    Raises:
        ExciteError: (``posture``) an unknown state, or no posture found; (``soles``) a given sole with no
            collision geometry or that is no link.
    """
    points = link_points(model, geometry)
    if not points:
        return None  # no geometry: nothing stands on the ground
    states = source.named_states()
    state = named_posture(states, asked)
    q = posture_vector(model, states[state] if state else {})
    legs, others = find_legs(model, points, q)
    if soles:
        missing = [s for s in soles if s not in points]
        if missing:
            raise ExciteError(
                "soles",
                f"'{missing[0]}' has no collision geometry in {source.path.name} (or is no link)",
                missing[0],
                ", ".join(points),
            )
        joints, every = {points[s][0] for s in soles}, legs + others
        legs = [c for c in every if joints & (_subtree(model, c[-1]) | set(c))]
        others = [c for c in every if c not in legs]
    if len(legs) < 2 and not soles:
        return None
    why = {}
    found = soles or sole_links(model, points, pin.neutral(model), legs)
    if state is None:
        q, why["robot.locked_joints"] = searched_posture(model, points, legs, found, pin.neutral(model))
    else:
        q, levelled = levelled_posture(model, points, legs, found, pin.neutral(model), q)
        why["robot.locked_joints"] = f"the state '{state}' of {source.states_file.name}" + levelled
    found = soles or sole_links(model, points, q, legs)
    placed = placed_points(model, q, points)
    floor = min(placed[s][:, 2].min() for s in found)
    contact = np.vstack([placed[s][placed[s][:, 2] <= floor + CONTACT_HEIGHT] for s in found])
    try:
        polygon = SupportPolygon.from_points(contact[:, :2], floor)
    except (QhullError, ValueError):
        raise ExciteError("soles", f"the soles {', '.join(found)} span no area on the floor", found) from None
    posture = {model.names[j]: float(q[model.idx_qs[j]]) for j in range(1, model.njoints) if model.joints[j].nq == 1}
    return Stance(
        posture=posture,
        legs=[[model.names[j] for j in c] for c in legs],
        arms=[[model.names[j] for j in c] for c in arm_chains(model, others)],
        soles=found,
        floor=float(floor),
        room=float(polygon.margins(polygon.centroid[None])[0]),
        why=why,
    )
