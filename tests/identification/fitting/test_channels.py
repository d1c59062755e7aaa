"""Torque channels without signal: weak against the URDF model's prediction by its variation (a constant
sensor offset is not signal), and their rows out of the fit only where the other joints still excite
every base parameter."""

import numpy as np

from excite_cli.identification.fitting.channels import WEAK, weak_channels, without_dead_rows
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.normal import NormalEquations


def test_a_channel_is_weak_by_its_variation_against_the_prediction():
    t = np.linspace(0.0, 10.0, 2001)
    predicted = np.column_stack([np.sin(t), 2.0 * np.cos(t), np.sin(3 * t), np.zeros_like(t)])
    measured = np.column_stack(
        [
            0.9 * WEAK * np.sin(t),  # varies below WEAK of the prediction: weak
            3.0 + 1.1 * WEAK * 2.0 * np.cos(t),  # above it, on a constant offset: not weak
            5.0 + 0.0 * t,  # a constant offset alone: weak
            1e-3 * np.sin(t),  # nothing predicted: never weak
        ]
    )
    assert list(weak_channels(np.std(measured, axis=0), np.std(predicted, axis=0))) == [True, False, True, False]


def _dataset(rows_per_joint: list[np.ndarray]) -> Dataset:
    """Two joints, base regressor rows (T, b) per joint, torques of base parameters (1, 2)."""
    T = rows_per_joint[0].shape[0]
    regressor = np.stack(rows_per_joint, axis=1).reshape(T * 2, -1)
    return Dataset(regressor, regressor @ np.array([1.0, 2.0]), np.arange(T) * 0.01, np.zeros(T, dtype=int), {})


def test_dead_rows_get_weight_zero_only_where_every_base_parameter_stays_excited():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(200, 2))
    live = np.array([True, False])
    shared = NormalEquations(_dataset([x, x]), [])  # joint 0 alone excites both parameters
    assert list(without_dead_rows(shared, None, live)) == [1.0, 0.0]
    assert list(without_dead_rows(shared, np.array([2.0, 3.0]), live)) == [2.0, 0.0]
    only = NormalEquations(_dataset([x * [1.0, 0.0], x * [0.0, 1.0]]), [])  # parameter 2 only on joint 1's rows
    assert without_dead_rows(only, None, live) is None
    np.testing.assert_array_equal(without_dead_rows(only, np.array([2.0, 3.0]), live), [2.0, 3.0])
    assert without_dead_rows(shared, None, np.array([True, True])) is None  # nothing dead: unchanged
