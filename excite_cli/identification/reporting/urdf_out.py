"""A copy of the robot's URDF with the identified inertial parameters, which pinocchio (or a simulator)
loads back.

Each body of the identification model is a moving joint's child link with everything locked or
fixed to it merged in (``Robot``). Its identified standard parameters are expressed in the joint's
frame, which is the child link's frame in URDF, so they are written to that link's ``<inertial>``
(mass, centre of mass, inertia about the centre of mass in the link's axes), and the links merged
into it lose theirs: the file then reproduces the identified model for the same active and locked
joints. Coulomb and viscous friction go to the joint's ``<dynamics friction damping>``; the other
effects are written as comments on their joint.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import pinocchio as pin

from excite_cli.atomic import MARK, atomic_path
from excite_cli.config import RobotConfig
from excite_cli.dynamics.mjcf_compiled import is_mjcf
from excite_cli.dynamics.robot import Robot, load_robot
from excite_cli.errors import ExciteError

#: Friction coefficients that URDF's <dynamics> carries: coefficient → attribute.
DYNAMICS = {"Fc": "friction", "Fv": "damping"}


def _number(value: float) -> str:
    return repr(float(value))


def _inertial(link: ET.Element, phi: np.ndarray) -> None:
    """Replace ``link``'s <inertial> by the body of standard parameters φ (10,)."""
    for old in link.findall("inertial"):
        link.remove(old)
    inertia = pin.Inertia.FromDynamicParameters(phi)
    element = ET.SubElement(link, "inertial")
    ET.SubElement(element, "origin", xyz=" ".join(_number(x) for x in inertia.lever), rpy="0 0 0")
    ET.SubElement(element, "mass", value=_number(inertia.mass))
    I = inertia.inertia
    ET.SubElement(
        element,
        "inertia",
        ixx=_number(I[0, 0]),
        ixy=_number(I[0, 1]),
        ixz=_number(I[0, 2]),
        iyy=_number(I[1, 1]),
        iyz=_number(I[1, 2]),
        izz=_number(I[2, 2]),
    )


def merged_links(robot: Robot) -> dict[str, list[str]]:
    """{body link: [links merged into it]} of the identification model (bodies in model order)."""
    model = robot.model
    out: dict[str, list[str]] = {name: [] for name in robot.body_names}
    for frame in model.frames:
        if frame.type == pin.FrameType.BODY and frame.parentJoint > 0:
            body = robot.body_names[frame.parentJoint - 1]
            if frame.name != body and frame.name not in out[body]:
                out[body].append(frame.name)
    return out


def check_urdf_source(source: Path) -> None:
    """That a URDF copy of the robot's file ``source`` can be written: it is a URDF, not an MJCF.

    Raises:
        ExciteError: (``urdf_out``) an MJCF.
    """
    if is_mjcf(source):
        problem = f"the robot's file {source.name} is an MJCF: a URDF copy of it cannot be written"
        raise ExciteError("urdf_out", problem, expected="the identified model as MJCF (mjcf_out)")


def write_urdf(
    source: Path,
    target: Path,
    robot: Robot,
    standard: np.ndarray,
    effects: list[tuple[str, str, str, float]],
    note: str,
) -> Path:
    """Write ``source`` with the identified inertias to ``target`` (atomically).

    Args:
        source: the URDF the identification used.
        robot: the identification model (bodies, merged links).
        standard: (p,) identified standard parameters φ, 10 per body [kg, kg·m, kg·m²].
        effects: (effect, coefficient, joint, value) of the identified effects (a coupled motor's
            ``joint`` is its motor coordinate, written as a comment).
        note: a line for the header comment (where the parameters come from).

    Raises:
        ExciteError: the URDF cannot be parsed, is an MJCF, lacks a body link, or the file cannot be
            written.
    """
    try:
        tree = ET.parse(source)
    except (ET.ParseError, OSError) as exc:
        raise ExciteError("robot.urdf", f"cannot parse {source}: {exc}") from None
    root = tree.getroot()
    check_urdf_source(source)
    links = {link.get("name"): link for link in root.findall("link")}
    joints = {joint.get("name"): joint for joint in root.findall("joint")}
    for i, (body, merged) in enumerate(merged_links(robot).items()):
        if body not in links:
            raise ExciteError("urdf_out", f"the body link '{body}' is not in {source}")
        _inertial(links[body], standard[10 * i : 10 * i + 10])
        for name in merged:
            for old in links[name].findall("inertial") if name in links else []:
                links[name].remove(old)
    for joint in robot.joint_names:  # the identified model: no friction where none was found
        dynamics = joints[joint].find("dynamics")
        if dynamics is None:
            dynamics = ET.SubElement(joints[joint], "dynamics")
        for attribute in DYNAMICS.values():
            dynamics.set(attribute, "0.0")
    for effect, coefficient, joint, value in effects:
        if joint not in joints:  # a motor turning with several joints: a URDF has no place for it
            root.append(ET.Comment(f" excite: {effect} {coefficient} of the motor of {joint} = {value:.6g} "))
        elif coefficient in DYNAMICS:
            joints[joint].find("dynamics").set(DYNAMICS[coefficient], _number(value))
        else:
            joints[joint].append(ET.Comment(f" excite: {effect} {coefficient} = {value:.6g} "))
    stamp = datetime.now(timezone.utc).isoformat(timespec="seconds")
    root.insert(
        0,
        ET.Comment(
            f" {MARK} identify, {stamp}: {note}. Links merged into a body (locked or fixed "
            f"joints) carry no <inertial>: their mass is in the body's. "
        ),
    )
    ET.indent(tree, space="  ")
    target = Path(target)
    with atomic_path(target, "urdf_out") as tmp:
        tree.write(tmp, encoding="utf-8", xml_declaration=True)
    return target


def urdf_deviation(cfg: RobotConfig, robot: Robot, torques, target: Path, samples: int = 200) -> float:
    """Largest |τ_URDF − τ_identified| [Nm] over ``samples`` random states: the written URDF (loaded
    by pinocchio with the same active and locked joints) against the identified model's rigid-body
    torques ``torques(q, q̇, q̈)`` → (n,). ``cfg`` is the ``robot`` section (joints).

    Raises:
        ExciteError: pinocchio cannot load the written file.
    """
    written = load_robot(cfg, urdf=Path(target).resolve(), joint_rows_only=True)
    states = robot.random_states(samples, np.random.default_rng(0))
    return float(max(np.abs(written.torques(*x) - torques(*x)).max() for x in zip(*states)))
