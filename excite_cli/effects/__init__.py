"""The effects a robot's model may lack beside the rigid body (friction, armature, offsets, springs,
coupled motors), one record each (:mod:`.catalogue`), for identification and design alike."""

from excite_cli.effects.catalogue import DESIGNED, EFFECT_NAMES, EFFECTS, NONNEGATIVE, SHAPE_GRID
from excite_cli.effects.record import Effect, Signals, held_sign, signals

__all__ = [
    "DESIGNED",
    "EFFECTS",
    "EFFECT_NAMES",
    "NONNEGATIVE",
    "SHAPE_GRID",
    "Effect",
    "Signals",
    "held_sign",
    "signals",
]
