"""An identification's rows as the next design's prior data: the chosen effects' columns named and
placed as a design of the same model has them."""

import numpy as np

from excite_cli.config import EffectsConfig, MotorConfig
from excite_cli.dynamics.effect_columns import effect_columns
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.reporting.prior_rows import prior_rows


def test_a_coupled_motor_and_an_offset_are_named_and_placed_as_a_design_has_them():
    """prior_rows of a two-joint dataset with a motor turning with both joints and an offset on the
    first: the names are those a design of the same model gives (effect_columns), the motor's block
    stands on both joints' rows times their transmission, the offset is ones on its joint's rows."""
    motor, offset = Term("motor", 0, coupling=(1.0, -2.0)), Term("offset", 0)
    cols = np.arange(9.0).reshape(3, 3)
    data = Dataset(
        np.ones((6, 4)), np.zeros(6), np.arange(3.0), np.zeros(3, int), {motor: cols, offset: np.ones((3, 1))}
    )
    rows = prior_rows([data], [offset, motor], ["a", "b"], (np.zeros(4), []))
    design = effect_columns(
        EffectsConfig(joints={"a": ["offset"]}, motors=[MotorConfig(joints=["a", "b"], transmission=[1.0, -2.0])]),
        ["a", "b"],
        2,
    )
    assert rows.effect_names == list(design.names)
    np.testing.assert_array_equal(rows.effects[0][:, 0], [1.0, 0.0] * 3)
    np.testing.assert_array_equal(rows.effects[0][0::2, 1:], cols)
    np.testing.assert_array_equal(rows.effects[0][1::2, 1:], -2.0 * cols)
