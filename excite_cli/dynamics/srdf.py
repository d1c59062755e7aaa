"""The postures a robot's SRDF names (MoveIt's Semantic Robot Description Format, ``<group_state name
group>`` with one ``<joint name value>`` per joint: wiki.ros.org/srdf), and where a URDF's SRDF is.

example-robot-data ships an SRDF beside most robots' URDF (``<package>/srdf/<name>.srdf`` beside
``<package>/urdf/`` or ``robots/``): ``half_sitting`` on its humanoids, ``standing`` or
``standing_with_arm_*`` on its legged robots. A multi-valued joint (the root's free flyer, ``x y z qx
qy qz qw``) is left out: excite holds the base at the identity.
"""

from __future__ import annotations

from pathlib import Path
from xml.etree import ElementTree

from excite_cli.errors import ExciteError


def srdf_states(path: Path) -> dict[str, dict[str, float]]:
    """{state name: {joint: value [rad or m]}} of the SRDF at ``path``, 1-DoF joints only, in the file's
    order.

    Raises:
        ExciteError: (``srdf``) a file that is not XML or not an SRDF (its root is not ``<robot>``), a
            joint value that is not a number.
    """
    try:
        root = ElementTree.parse(path).getroot()
    except (ElementTree.ParseError, OSError) as exc:
        raise ExciteError("srdf", f"cannot read {path}: {' '.join(str(exc).split())[:200]}") from None
    if root.tag != "robot":
        raise ExciteError("srdf", f"{path.name} is not an SRDF (its root element is <{root.tag}>)", None, "<robot>")
    states: dict[str, dict[str, float]] = {}
    for state in root.iter("group_state"):
        values = {}
        for joint in state.iter("joint"):
            words = (joint.get("value") or "").split()
            if len(words) != 1:
                continue  # a free flyer's pose, or nothing
            try:
                values[joint.get("name")] = float(words[0])
            except ValueError:
                raise ExciteError(
                    "srdf",
                    f"{path.name}: state '{state.get('name')}' gives joint '{joint.get('name')}' "
                    f"the value {words[0]!r}",
                    words[0],
                    "a number [rad or m]",
                ) from None
        states.setdefault(state.get("name") or f"state{len(states)}", values)
    return states


def _robot_name(path: Path) -> str:
    try:
        return (ElementTree.parse(path).getroot().get("name") or "").lower()
    except (ElementTree.ParseError, OSError):
        return ""


def srdf_beside(urdf: Path) -> Path | None:
    """The SRDF of ``urdf``, or None: in the URDF's folder or a sibling ``srdf`` folder, the file of the
    URDF's own name (``b1-z1.srdf`` for ``b1-z1.urdf``), else the one file there naming the same robot
    (``<robot name>``; ``talos.srdf`` for ``talos_reduced.urdf``); of several of that robot, the one
    whose name the URDF's begins with, else none (give ``--srdf``)."""
    folders = [urdf.parent, urdf.parent.parent / "srdf"]
    candidates = [p for folder in folders if folder.is_dir() for p in sorted(folder.glob("*.srdf"))]
    same_stem = [p for p in candidates if p.stem == urdf.stem]
    if same_stem:
        return same_stem[0]
    name = _robot_name(urdf)
    same_robot = [p for p in candidates if name and _robot_name(p) == name]
    if len(same_robot) > 1:
        same_robot = [p for p in same_robot if urdf.stem.startswith(p.stem)]
    return same_robot[0] if len(same_robot) == 1 else None
