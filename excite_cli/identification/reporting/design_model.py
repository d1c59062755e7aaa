"""The effects an identify report chose, as the model the next trajectory is designed for
(``effects.model`` of an ``optimize`` config): each joint's Coulomb and viscous friction, armature and
torque offset, and each coupled motor with its transmission row (``/identification/effect_coupling``).
Effects the design cannot hold as columns (asymmetric, Stribeck, held and load-dependent friction:
nonlinear in a shape or a first fit; springs and position harmonics) are named and left out."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from excite_cli.config import EffectsConfig, MotorConfig
from excite_cli.errors import ExciteError, ExciteWarning
from excite_cli.h5 import open_h5, read_strings

#: The report's effects that are design columns (:data:`excite_cli.config.effects.JointEffect`).
DESIGNED = ("coulomb", "viscous", "armature", "offset")


@dataclass(frozen=True)
class ReportModel:
    """The designable part of an identify report's model.

    Attributes:
        joints: {joint: [effects among ``DESIGNED``]}.
        motors: coupled motors: (joints, transmission row) each.
        coulomb_velocity: v_c [rad/s] of the report's smooth sign.
        left_out: the report's other effects, as ``effect (joint)``.
    """

    joints: dict[str, list[str]]
    motors: list[tuple[list[str], list[float]]]
    coulomb_velocity: float
    left_out: list[str]


def _text(value: object) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)


def read_report_model(path: Path) -> ReportModel:
    """The model of the identify report at ``path`` (``/identification/effects``, ``effect_coupling``,
    ``joint_names`` and the attribute ``coulomb_velocity_rad_s``).

    Raises:
        FileNotFound, ExciteError: (``effects.model``) no readable file, or not an identify report.
    """
    with open_h5(path, "effects.model") as f:
        if "identification/effects" not in f:
            raise ExciteError("effects.model", f"{path} is not an identify report (no /identification/effects)")
        g = f["identification"]
        rows, coupling = g["effects"][()], g["effect_coupling"][()]
        names = read_strings(g, "joint_names")
        velocity = float(g.attrs.get("coulomb_velocity_rad_s", 0.01))
    joints: dict[str, list[str]] = {}
    motors: list[tuple[list[str], list[float]]] = []
    left_out: list[str] = []
    for row, weights in zip(rows, coupling):
        effect, joint = _text(row["effect"]), _text(row["joint"])
        if effect == "motor":
            moved = np.flatnonzero(weights)
            motor = ([names[k] for k in moved], [float(weights[k]) for k in moved])
            motors += [] if motor in motors else [motor]
        elif effect in DESIGNED:
            kinds = joints.setdefault(joint, [])
            kinds += [] if effect in kinds else [effect]
        elif f"{effect} ({joint})" not in left_out:
            left_out.append(f"{effect} ({joint})")
    return ReportModel(joints, motors, velocity, left_out)


def with_report_model(cfg: EffectsConfig, path: Path, joint_names: list[str]) -> EffectsConfig:
    """``cfg`` with the effects of the identify report at ``path`` added (the report's smooth-sign
    velocity taken); an :class:`~excite_cli.errors.ExciteWarning` names the effects left out.

    Raises:
        ExciteError: (``effects.model``) not an identify report, or one whose joints are not all
            active in this problem (a report of another robot or joint set).
    """
    model = read_report_model(path)
    unknown = [j for j in [*model.joints, *(j for joints, _ in model.motors for j in joints)] if j not in joint_names]
    if unknown:
        raise ExciteError(
            "effects.model", f"{path} identified joint '{unknown[0]}', which is not an active joint of this problem"
        )
    if model.left_out:
        warnings.warn(
            f"effects.model: {', '.join(model.left_out)} from {path.name} are not designed for (nonlinear in a "
            "shape, or position-dependent)",
            ExciteWarning,
        )
    joints = {name: list(kinds) for name, kinds in cfg.joints.items()}
    for name, kinds in model.joints.items():
        joints[name] = joints.get(name, []) + [k for k in kinds if k not in joints.get(name, [])]
    motors = list(cfg.motors) + [MotorConfig(joints=j, transmission=t) for j, t in model.motors]
    return cfg.model_copy(update={"joints": joints, "motors": motors, "coulomb_velocity": model.coulomb_velocity})
