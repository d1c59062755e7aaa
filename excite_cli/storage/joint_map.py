"""Joints named as the controller names them: ``export --joint-names``.

A robot's file and its controller often name the joints differently (an MJCF's ``joint1…joint7``,
a ros2_control description's ``fr3_joint1…``), and a ``joint_trajectory_controller`` refuses a
trajectory naming a joint it does not have (ros2_controllers, ``validate_trajectory_msg``:
"Incoming joint ... doesn't match the controller's joints"). The map renames the exported joints
(active and held) in every format; each key must be a joint of the export, the new names distinct.
Given inline (``joint1=fr3_joint1,joint2=fr3_joint2``) or as a YAML file of ``{robot: controller}``.
"""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

from excite_cli.config_file import read_yaml
from excite_cli.errors import ExciteError
from excite_cli.storage.export import Export

#: A joint name a controller can hold: a ROS 2 name's characters (ROS 2 topic and parameter names).
NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_/]*$")


def read_joint_map(given: str) -> dict[str, str]:
    """The map ``given`` inline (``robot=controller`` pairs separated by commas) or as the path of a
    YAML file holding one mapping: {robot joint: controller joint}.

    Raises:
        ExciteError: (``joint_names``) a pair without ``=``, a joint named twice, a file that is not one
            mapping of names, a name a controller cannot hold.
    """
    path = Path(given)
    if "=" not in given and path.suffix.lower() in (".yaml", ".yml", ".json"):
        value, _ = read_yaml(path, "joint_names")
        if not isinstance(value, dict) or not all(isinstance(k, str) and isinstance(v, str) for k, v in value.items()):
            problem = f"{path.name} is not one mapping of joint names"
            raise ExciteError("joint_names", problem, expected="robot joint: controller joint")
        pairs = dict(value)
    else:
        pairs = {}
        for item in filter(None, (part.strip() for part in given.split(","))):
            if item.count("=") != 1:
                raise ExciteError("joint_names", f"'{item}' is not robot=controller", item, "robot=controller pairs")
            key, _, name = (part.strip() for part in item.partition("="))
            if key in pairs:  # as a YAML mapping refuses a repeated key
                raise ExciteError(
                    "joint_names", f"'{key}' is named twice ({key}={pairs[key]}, {item})", key, "each joint once"
                )
            pairs[key] = name
    for name in pairs.values():
        if not NAME.match(name):
            raise ExciteError("joint_names", f"'{name}' is not a joint name a controller can hold", name)
    return pairs


def renamed(export: Export, mapping: dict[str, str]) -> Export:
    """``export`` with its active and held joints renamed by ``mapping`` (others keep their names).

    Raises:
        ExciteError: (``joint_names``) a key that is not a joint of the export (the joints named), or
            two joints given one name.
    """
    held = export.held.joint_names if export.held else ()
    joints = [*export.joint_names, *held]
    unknown = [k for k in mapping if k not in joints]
    if unknown:
        raise ExciteError(
            "joint_names", f"'{unknown[0]}' is not a joint of the export", unknown[0], f"one of {', '.join(joints)}"
        )
    names = [mapping.get(j, j) for j in joints]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ExciteError("joint_names", f"two joints would be called '{twice[0]}'", twice[0], "distinct names")
    n = len(export.joint_names)
    moved = replace(export.held, joint_names=tuple(names[n:])) if export.held else None
    return replace(export, joint_names=names[:n], held=moved)
