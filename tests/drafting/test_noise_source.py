"""The noise section drafted for where the torques come from: the weights it gives the regressor rows
(:mod:`excite_cli.design.noise`) follow the noise each source has."""

import numpy as np
import pytest

from excite_cli.config import NoiseConfig
from excite_cli.drafting.noise_source import CURRENT_FLOOR, RELATIVE, SENSOR_FLOOR, draft_noise

JOINTS, TYPICAL = ["a", "b"], np.array([10.0, 0.5])


def test_a_torque_sensor_gets_absolute_noise_scaled_by_each_joints_typical_torque():
    section, why = draft_noise("sensor", JOINTS, TYPICAL)
    cfg = NoiseConfig(**section)
    assert cfg.relative == 0.0 and cfg.absolute == {"a": SENSOR_FLOOR * 10.0, "b": SENSOR_FLOOR * 0.5}
    assert why.startswith("torque from joint torque sensors: absolute noise")


def test_motor_current_gets_noise_growing_with_the_torque_over_a_floor():
    section, why = draft_noise("current", JOINTS, TYPICAL)
    cfg = NoiseConfig(**section)
    assert cfg.relative == RELATIVE and cfg.absolute == pytest.approx(
        {"a": CURRENT_FLOOR * 10.0, "b": CURRENT_FLOOR * 0.5}
    )
    # at the typical torque the relative part is RELATIVE / CURRENT_FLOOR (10) times the floor
    variance = np.array(list(cfg.absolute.values())) ** 2 + (RELATIVE * TYPICAL) ** 2
    np.testing.assert_allclose(variance, (TYPICAL * CURRENT_FLOOR) ** 2 * (1 + (RELATIVE / CURRENT_FLOOR) ** 2))
    assert why.startswith("torque from motor current: 2% of the torque over a floor of 0.2%")


def test_an_unknown_source_drafts_no_section_and_says_how_to_declare_one():
    section, why = draft_noise("unknown", JOINTS, TYPICAL)
    assert section is None and why.startswith("none: the torque source was not said")
