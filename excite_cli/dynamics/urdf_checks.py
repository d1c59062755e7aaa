"""A robot that can be: the URDF's inertial parameters and the active joints' limits checked when the
robot is loaded, each problem named by link or joint in one line. pinocchio takes a URDF as it is
(a negative mass, a NaN urdfdom could not parse and left at 0, a lower limit above the upper one);
the dynamics of such a model are meaningless (export once wrote torques of 3e92 Nm).

Every link with an ``<inertial>``: the mass m and the inertia entries are finite numbers and m ≥ 0.
Links an active joint moves (their inertia is in the regressor of the problem) also need principal
moments I₁ ≤ I₂ ≤ I₃ about the centre of mass that are ≥ 0 and satisfy the triangle inequality
I₁ + I₂ ≥ I₃ (both within ``TOLERANCE`` of I₃): exactly "some positive mass distribution has this
inertia" (Traversaro, Brossette, Escande, Nori, IROS 2016). The links no active joint moves are
not held to it: 46 of the 2149 links of example-robot-data's URDFs break it (sensor mounts of the
PR2, fingers of the Allegro hand, Romeo's torso), and refusing a robot for a link the problem does
not move would refuse valid work. Per active joint: the limits are numbers and lower ≤ upper. A
``<mimic>`` joint follows another in a way the model does not represent, so it may not be active;
the joint it follows may, but the follower is then held still while its leader moves, so it must be
listed in ``robot.locked_joints`` (held on purpose, as the Panda's second finger when the first is
active): otherwise the model would silently differ from the robot.

The file is a URDF at all (:func:`check_is_urdf`): a vendor's ``.xacro`` as shipped parsed as a URDF
with every joint fixed. Links an active joint moves that have
no mass (ROS-Industrial's KUKA iiwa has no ``<inertial>`` anywhere) are said in a warning: the
regressor does not need their inertias, but the feed-forward torque and the torque limits do.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from xml.etree import ElementTree

import numpy as np

from excite_cli.errors import ExciteError, ExciteWarning

#: Relative tolerance of the principal-moment checks (CAD exports round their inertias).
TOLERANCE = 1e-6
#: Largest number of links of a URDF (example-robot-data's largest has 130; pinocchio's parser
#: crashes on a chain of 4 000).
MAX_LINKS = 1000
INERTIA = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
LIMITS = ("lower", "upper", "effort", "velocity")
#: The namespace xacro's macros are written in.
XACRO = "{http://www.ros.org/wiki/xacro}"


def check_is_urdf(root: ElementTree.Element, path: Path) -> None:
    """That the XML at ``path`` (its ``root`` element) is a URDF, not a xacro file to expand first
    (an MJCF is read by :mod:`~excite_cli.dynamics.mjcf_source`, not here).

    Raises:
        ExciteError: (``robot.urdf``) a xacro file (its ending or xacro elements), naming the command that
            expands it, or another root element than ``<robot>``.
    """
    if path.name.endswith(".xacro") or any(e.tag.startswith(XACRO) for e in root.iter()):
        raise ExciteError(
            "robot.urdf",
            f"{path.name} is a xacro file: its macros are not expanded",
            expected=f"the URDF it expands to: xacro {path.name} > robot.urdf (pip install xacro, or "
            f"ros2 run xacro xacro {path.name}), then robot.urdf: robot.urdf",
        )
    if root.tag != "robot":
        raise ExciteError("robot.urdf", f"{path.name} is not a URDF: its root element is <{root.tag}>, not <robot>")


def _number(element: ElementTree.Element, attribute: str, what: str) -> float:
    """``attribute`` of ``element`` as a finite float (absent: 0).

    Raises:
        ExciteError: not a finite number.
    """
    text = element.get(attribute, "0")
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise ExciteError("robot.urdf", f"{what} {attribute} is '{text}'", text, "a finite number")
    return value


def check_inertial(link: ElementTree.Element, moved: bool = True) -> str:
    """The inertial parameters of one URDF ``<link>`` (module docstring); ``moved``: an active joint
    moves it (its principal moments are checked).

    Returns:
        The principal moments' problem in words (the link's inertia no body can have), or "".

    Raises:
        ExciteError: naming the link and what is wrong (a mass or inertia that is not a number, a
            negative mass).
    """
    inertial = link.find("inertial")
    if inertial is None:
        return ""
    name = f"link '{link.get('name')}'"
    mass = inertial.find("mass")
    m = 0.0 if mass is None else _number(mass, "value", f"{name}: mass")
    if m < 0.0:
        raise ExciteError("robot.urdf", f"{name} has a negative mass ({m:g} kg)", m, "a mass ≥ 0 kg")
    element = inertial.find("inertia")
    if element is None:
        return ""
    ixx, ixy, ixz, iyy, iyz, izz = (_number(element, k, f"{name}: inertia") for k in INERTIA)
    if not moved:
        return ""
    moments = np.linalg.eigvalsh(np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]))
    slack = TOLERANCE * max(abs(moments[2]), 1e-12)
    if moments[0] < -slack or moments[0] + moments[1] < moments[2] - slack:
        return (
            f"{name} has an inertia no body can have (principal moments {', '.join(f'{x:.4g}' for x in moments)} kg·m²)"
        )
    return ""


def check_joints(root: ElementTree.Element, active: list[str], locked: list[str] = ()) -> None:
    """Limits and ``<mimic>`` of the active joints (module docstring); ``locked``: the joints held on
    purpose (``robot.locked_joints``).

    Raises:
        ExciteError: naming the joint.
    """
    joints = {j.get("name"): j for j in root.findall("joint")}
    for name in active:
        limit = None if name not in joints else joints[name].find("limit")
        if limit is None:
            continue
        lower, upper, _, _ = (_number(limit, k, f"joint '{name}': limit") for k in LIMITS)
        if lower > upper and joints[name].get("type") != "continuous":
            problem = f"joint '{name}' has lower limit {lower:g} above upper {upper:g}"
            raise ExciteError("robot.urdf", problem, None, "lower ≤ upper")
    check_couplings(urdf_couplings(root), active, locked)


def urdf_couplings(root: ElementTree.Element) -> dict[str, tuple[str, str]]:
    """{follower: (leader, how, in words)} of the URDF's ``<mimic>`` joints (its ``root`` element)."""
    couplings = {}
    for joint in root.iter("joint"):
        mimic = joint.find("mimic")
        if mimic is not None:
            how = f"multiplier {mimic.get('multiplier', '1')}, offset {mimic.get('offset', '0')}"
            couplings[joint.get("name")] = (mimic.get("joint"), how)
    return couplings


def check_couplings(couplings: dict[str, tuple[str, str]], active: list[str], locked: list[str] = ()) -> None:
    """Joints that follow another (a URDF ``<mimic>``, an MJCF joint equality): {follower: (leader,
    how, in words)}. A follower may not be active; one whose leader is active must be held on purpose
    (in ``locked``), as the module docstring says.

    Raises:
        ExciteError: (``robot.active_joints`` or ``robot.locked_joints``) naming the joint.
    """
    for name, (followed, how) in couplings.items():
        if name in active:
            raise ExciteError(
                "robot.active_joints",
                f"joint '{name}' mimics '{followed}', a coupling the model does not represent",
                name,
                "active joints that follow no other",
            )
        if followed in active and name not in locked:
            raise ExciteError(
                "robot.locked_joints",
                f"joint '{name}' mimics active joint '{followed}' ({how}), a coupling the model does not "
                f"represent: it would be held still while '{followed}' moves",
                name,
                f"'{name}' listed in robot.locked_joints (held on purpose) or '{followed}' not active",
            )


def _warn_massless(root: ElementTree.Element, active: list[str], children: dict[str, list[str]], path: Path) -> None:
    """An :class:`~excite_cli.errors.ExciteWarning` naming the ``active`` joints of the URDF at ``path``
    (its ``root``; ``children``: link → child links) that move no mass at all: their torque is 0
    whatever the motion (a frame with no mass is common; a whole arm without is a URDF without
    inertias)."""
    masses = {}
    for link in root.findall("link"):
        mass = link.find("inertial/mass")
        masses[link.get("name")] = 0.0 if mass is None else _number(mass, "value", f"link '{link.get('name')}': mass")
    idle = []
    for joint in root.findall("joint"):
        child = joint.find("child")
        if joint.get("name") not in active or child is None:
            continue
        subtree, total = [child.get("link")], 0.0
        while subtree:
            link = subtree.pop()
            total += masses.get(link, 0.0)
            subtree += children.get(link, [])
        if not total > 0.0:
            idle.append(joint.get("name"))
    if idle:
        warnings.warn(
            f"{path.name} gives no mass to anything {', '.join(idle)} move(s): their torque is 0 whatever the "
            "motion (no <inertial> in the URDF?); the trajectory still excites them, but the feed-forward torque "
            "export writes is 0 there and torque limits cannot be checked",
            ExciteWarning,
            stacklevel=3,
        )


def check_tree(links: list[str], parents: dict[str, list[str]], children: dict[str, list[str]]) -> None:
    """The links and joints of a URDF form one tree of at most :data:`MAX_LINKS` links: no link is the
    child of two joints (a closed kinematic chain, which a URDF cannot describe and pinocchio
    misreads), one link is the root and every link hangs from it (links that do not form a ring of
    joints beside the tree, which pinocchio leaves out).

    Args:
        links: every ``<link>``'s name.
        parents: the joints that have each link as their child.
        children: the child links of each link.

    Raises:
        ExciteError: (``robot.urdf``) more links than :data:`MAX_LINKS`, a link with two parent
            joints, no root link or links that do not hang from it (a ring, named by its joints).
    """
    if len(links) > MAX_LINKS:
        raise ExciteError(
            "robot.urdf",
            f"the URDF has {len(links)} links",
            len(links),
            f"at most {MAX_LINKS} (pinocchio's parser crashes)",
        )
    for link, joints in parents.items():
        if len(joints) > 1:
            raise ExciteError(
                "robot.urdf",
                f"link '{link}' is the child of {len(joints)} joints ({', '.join(repr(j) for j in joints)}): "
                "a closed kinematic chain, which a URDF cannot describe",
                link,
                "a tree of links (one parent joint per link)",
            )
    roots = [link for link in links if link not in parents]
    hanging, below = set(roots[:1]), list(roots[:1])
    while below:
        hanging.update(below)
        below = [c for link in below for c in children.get(link, []) if c not in hanging]
    ring = [parents[link][0] for link in links if link not in hanging and link in parents]
    if ring:
        raise ExciteError(
            "robot.urdf",
            f"joints {', '.join(repr(j) for j in ring)} form a closed kinematic chain"
            + (f" apart from the root link '{roots[0]}'" if roots else ""),
            None,
            "a tree of links (one root, one parent joint per link)",
        )


def check_urdf(path: Path, active: list[str], physical: bool = True, locked: list[str] = ()) -> list[str]:
    """Every check of the module docstring on the URDF at ``path``.

    Args:
        active: the active joints' names.
        locked: the joints held on purpose (``robot.locked_joints``).
        physical: refuse a moved link whose inertia no body can have; False (identification, which
            uses the URDF's inertias as a reference only, and vendors' URDFs often break the triangle
            inequality): return such links' problems in words instead.

    Returns:
        The moved links' inertias no body can have, in words (empty with ``physical``).

    Raises:
        ExciteError: the file is not XML, links that are no tree (:func:`check_tree`), a mass or
            inertia that is not a number, a negative mass, an active joint that cannot be, or (with
            ``physical``) an inertia no body can have.
    """
    try:
        root = ElementTree.parse(path).getroot()
    except (ElementTree.ParseError, OSError) as exc:
        raise ExciteError("robot.urdf", f"cannot read {path}: {exc}") from None
    check_is_urdf(root, path)
    children: dict[str, list[str]] = {}
    parents: dict[str, list[str]] = {}
    moved: list[str] = []
    below: set[str] = set()
    for joint in root.findall("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is not None and child is not None:
            children.setdefault(parent.get("link"), []).append(child.get("link"))
            parents.setdefault(child.get("link"), []).append(joint.get("name"))
            moved += [child.get("link")] if joint.get("name") in active else []
    check_tree([link.get("name") for link in root.findall("link")], parents, children)
    while moved:  # every link below an active joint
        link = moved.pop()
        below.add(link)
        moved += [c for c in children.get(link, []) if c not in below]
    problems = [p for link in root.findall("link") if (p := check_inertial(link, link.get("name") in below))]
    _warn_massless(root, active, children, path)
    if problems and physical:
        raise ExciteError(
            "robot.urdf", problems[0], None, "moments ≥ 0 with the two smaller summing to at least the largest"
        )
    check_joints(root, active, locked)
    return problems
