"""The noise section drafted for where the torques come from: the weights it gives the regressor rows
(:mod:`excite_cli.design.noise`) follow the noise each source has."""

import numpy as np
import pytest

from excite_cli.config import NoiseConfig
from excite_cli.drafting.noise_source import CURRENT_FLOOR, HEDGE_FLOOR, RELATIVE, SENSOR_FLOOR, draft_noise

JOINTS, TYPICAL = ["a", "b"], np.array([10.0, 0.5])


def test_a_torque_sensor_gets_absolute_noise_scaled_by_each_joints_typical_torque():
    section, why = draft_noise("sensor", JOINTS, TYPICAL)
    cfg = NoiseConfig(**section)
    assert cfg.relative == 0.0 and cfg.absolute == {"a": SENSOR_FLOOR * 10.0, "b": SENSOR_FLOOR * 0.5}
    assert why.startswith("torque from joint torque sensors: absolute noise")


@pytest.mark.parametrize("source, floor", [("current", CURRENT_FLOOR), ("unknown", HEDGE_FLOOR)])
def test_motor_current_and_an_unknown_source_get_noise_growing_with_the_torque_over_a_floor(source, floor):
    section, why = draft_noise(source, JOINTS, TYPICAL)
    cfg = NoiseConfig(**section)
    assert cfg.relative == RELATIVE and cfg.absolute == pytest.approx({"a": floor * 10.0, "b": floor * 0.5})
    # at the typical torque the relative part is RELATIVE / floor times the floor
    variance = np.array(list(cfg.absolute.values())) ** 2 + (RELATIVE * TYPICAL) ** 2
    np.testing.assert_allclose(variance, (TYPICAL * floor) ** 2 * (1 + (RELATIVE / floor) ** 2))
    assert why.startswith("torque from motor current" if source == "current" else "torque source not said")
