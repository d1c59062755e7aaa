"""The ``effects`` section: what it accepts and refuses, by field."""

import pytest
from pydantic import ValidationError

from excite_cli.config.effects import EffectsConfig, MotorConfig


def test_joints_take_the_designable_effects_and_motors_a_transmission_row():
    cfg = EffectsConfig(
        joints={"*": ["coulomb", "viscous"], "elbow": ["armature", "offset"]},
        motors=[MotorConfig(joints=["w2", "w3"], transmission=[1.0, 1.0])],
    )
    assert cfg.coulomb_velocity == 0.01 and cfg.motors[0].transmission == [1.0, 1.0] and cfg.model is None
    assert EffectsConfig().joints == {} and EffectsConfig().motors == []


@pytest.mark.parametrize(
    "data, field",
    [
        ({"joints": {"*": ["stribeck"]}}, "joints"),  # nonlinear in its shape: identify's, not a design column
        ({"coulomb_velocity": 0.0}, "coulomb_velocity"),
        ({"motors": [{"joints": ["a"], "transmission": [0.0]}]}, "transmission"),
        ({"motors": [{"joints": [], "transmission": []}]}, "joints"),
        ({"motors": [{"joints": ["a", "b"], "transmission": [1.0, 1e300]}]}, "another unit"),  # issue 62
        ({"motors": [{"joints": ["a", "a"], "transmission": [1.0, -1.0]}]}, "named twice"),  # issue 62
        ({"friction": ["coulomb"]}, "friction"),
    ],
)
def test_what_cannot_be_designed_for_is_refused_naming_the_field(data, field):
    with pytest.raises(ValidationError, match=field):
        EffectsConfig(**data)
