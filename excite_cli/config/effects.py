"""The ``effects`` section of an ``optimize`` config: the identification model beyond the rigid body a
trajectory is designed for (its effect columns stand beside the base regressor's in the criterion)."""

from __future__ import annotations

import math
from typing import Literal, Optional

from pydantic import Field, PositiveFloat, field_validator

from excite_cli.config.base import COULOMB_VELOCITY, Section
from excite_cli.effects import DESIGNED

#: The effects a joint's columns can hold (:data:`excite_cli.effects.DESIGNED`): linear in their
#: coefficients, functions of q̇ and q̈ alone, so the optimizer can excite them (Coulomb through a smooth sign).
JointEffect = Literal[DESIGNED]


#: Largest transmission ratio or gear ratio taken as a ratio [1]: beyond it the number is in another unit.
MAX_RATIO = 1e6


class MotorConfig(Section):
    """A motor that turns with several joints (a coupled wrist: s = q5 + q6): its rotor inertia, Coulomb
    and viscous friction in the motor coordinate s = Σ_k n_k q_k, whose torque reaches joint k times n_k."""

    joints: list[str] = Field(min_length=1)
    """The joints the motor turns with."""
    transmission: list[float] = Field(min_length=1)
    """n_k [1], one per joint in `joints`: s = Σ n_k q_k (the transmission row of the motor)."""

    @field_validator("transmission")
    @classmethod
    def _nonzero(cls, value: list[float]) -> list[float]:
        if not any(value):
            raise ValueError("a transmission row of zeros moves no joint")
        if not all(math.isfinite(n) and abs(n) <= MAX_RATIO for n in value):
            raise ValueError(f"every n_k must be a finite number of at most {MAX_RATIO:g} in size (another unit?)")
        return value

    @field_validator("joints")
    @classmethod
    def _distinct(cls, value: list[str]) -> list[str]:
        if len(set(value)) != len(value):
            raise ValueError("a joint is named twice; give each joint once with its n_k")
        return value


class EffectsConfig(Section):
    """Effects beyond the rigid body the trajectory is designed to excite (none by default: the
    paper's rigid-body base parameters only)."""

    joints: dict[str, list[JointEffect]] = Field(default_factory=dict)
    """{joint or '*': [coulomb, viscous, armature, offset]}: each a column on that joint's row."""
    motors: list[MotorConfig] = Field(default_factory=list)
    """Coupled motors, each with its inertia, Coulomb and viscous friction in the motor coordinate."""
    coulomb_velocity: PositiveFloat = COULOMB_VELOCITY
    """v_c [rad/s] of the smooth sign tanh(q̇/v_c) of Coulomb friction (as identify's default)."""
    model: Optional[str] = None
    """An identify report whose chosen effects are added (its v_c taken); relative to this file."""
