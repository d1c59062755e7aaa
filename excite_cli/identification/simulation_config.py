"""The effects file of ``excite simulate``: what the simulated robot has beyond its URDF rigid body
(effects per joint, a transmission and its motors' effects, noise, jitter, sample rate)."""

from __future__ import annotations

from typing import Literal, Optional, Union

from pydantic import Field, model_validator

from excite_cli.config import COULOMB_VELOCITY, MAX_SEED, Section
from excite_cli.effects import EFFECTS
from excite_cli.identification.config import Effect
from excite_cli.identification.data_config import MAX_RATE, TransmissionConfig


class SimulationConfig(Section):
    """``excite simulate`` effects file: what the simulated robot has beyond its URDF rigid body."""

    sample_rate: float = Field(1000.0, gt=0.0, le=MAX_RATE)
    """Sample rate [Hz] of the simulated runs."""
    periods: int = Field(2, ge=1, le=1000)
    """Periods of the trajectory each run plays."""
    timestamp_jitter: float = Field(0.0, ge=0.0, lt=0.5)
    """Jitter of the time stamps [1], a fraction of the sample period."""
    torque_noise: float = Field(0.0, ge=0.0)
    """Standard deviation of the torque noise [Nm] (its part that does not grow with the torque)."""
    torque_noise_relative: float = Field(0.0, ge=0.0, le=10.0)
    """ρ [1]: torque noise growing with the torque, as a motor current's: σ(t) = √(torque_noise² + (ρ τ(t))²)."""
    position_noise: float = Field(0.0, ge=0.0)
    """Standard deviation of the position noise [rad]."""
    seed: int = Field(0, ge=0, le=MAX_SEED)
    """Seed of the noise and jitter."""
    effects: dict[Effect, dict[str, Union[float, tuple[float, float]]]] = Field(default_factory=dict)
    """{effect: {joint or '*': coefficient}}: the identification's coefficients [in their units: Nm, Nm·s/rad]."""
    stribeck_velocity: float = Field(0.1, gt=0.0)
    """Stribeck's v_s [rad/s]."""
    coulomb_velocity: float = Field(COULOMB_VELOCITY, gt=0.0)
    """v_c of the smooth sign [rad/s]."""
    held_velocity: float = Field(0.02, gt=0.0)
    """Held friction's v_h [rad/s]."""
    transmission: Optional[TransmissionConfig] = None
    """Gear ratios and coupling of the motors, or none."""
    motor_effects: dict[Literal[EFFECTS["motor"].parts], dict[str, float]] = Field(default_factory=dict)
    """{armature|coulomb|viscous: {motor's joint or \"*\": value}}: each motor's own [kg·m², Nm, Nm·s/rad]."""
    motor_side: bool = False
    """Write motor angles and motor torques (m = R q, τ_m = R⁻ᵀ τ)."""
    recording: Literal["csv", "rosbag2"] = "csv"
    """`csv` (a file per run) or `rosbag2` (a bag folder per run, as `ros2 bag record /joint_states` writes)."""

    @model_validator(mode="after")
    def _motors_need_the_transmission(self) -> "SimulationConfig":
        if (self.motor_effects or self.motor_side) and self.transmission is None:
            raise ValueError("motor_effects and motor_side need a transmission (gear ratios and coupling)")
        return self
