"""The ``rehearsal:`` section: the controller a lab runs, as ``excite rehearse`` plays it in MuJoCo."""

from __future__ import annotations

from typing import Optional

from pydantic import Field, NonNegativeFloat, PositiveFloat

from excite_cli.config.base import Section


class GainsConfig(Section):
    """A joint PD: τ = K (q_ref − q) + D (q̇_ref − q̇), the same for every joint unless ``per_joint`` says."""

    stiffness: PositiveFloat
    """K [N·m/rad]."""
    damping: NonNegativeFloat
    """D [N·m·s/rad]."""
    per_joint: dict[str, tuple[PositiveFloat, NonNegativeFloat]] = Field(default_factory=dict)
    """{joint: [K, D]} where a joint's gains differ."""

    def of(self, joint: str) -> tuple[float, float]:
        """(K, D) of ``joint``."""
        return self.per_joint.get(joint, (self.stiffness, self.damping))


class JointLossesConfig(Section):
    """What every joint has that a URDF does not say (MuJoCo documentation, XML reference, joint); a lab's
    MJCF keeps its own."""

    damping: NonNegativeFloat = 0.0
    """Viscous friction [N·m·s/rad] (MuJoCo's joint ``damping``)."""
    armature: NonNegativeFloat = 0.0
    """Rotor inertia [kg·m²] (``armature``)."""
    frictionloss: NonNegativeFloat = 0.0
    """Dry friction [N·m] (``frictionloss``)."""


class RehearsalConfig(Section):
    """The controller ``excite rehearse`` plays the export with: the active joints on the exported
    feed-forward plus a PD, a standing robot's held joints on a PD with or without the exported held-joint
    feed-forward, at the controller's rate (each command held until the next)."""

    rate: PositiveFloat = Field(1000.0, le=20_000.0)
    """Controller rate [Hz]: the export's samples, each held for 1 / rate."""
    active_gains: GainsConfig = GainsConfig(stiffness=200.0, damping=10.0)
    """The PD the active joints track the export with, beside its feed-forward torque."""
    held_gains: GainsConfig = GainsConfig(stiffness=1000.0, damping=40.0)
    """The PD that holds a standing robot's other joints at their locked values."""
    held_feedforward: bool = True
    """The held joints also get the export's held-joint feed-forward (False: PD alone)."""
    joint_losses: Optional[JointLossesConfig] = None
    """Damping, armature and dry friction of every joint of the URDF; none: zero (a lab's MJCF keeps its own)."""
