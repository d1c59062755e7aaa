"""Effect records' helpers: the history-dependent sign of held friction, the smooth sign's signals."""

import numpy as np

from excite_cli.effects.record import held_sign, signals


def test_held_sign_keeps_the_sign_of_the_last_motion_faster_than_v_h():
    """Below v_h the sign is that of the last sample at or above v_h (0 before any); moving, it is 0."""
    qd = np.array([0.0, 0.05, 0.2, 0.05, -0.01, -0.3, 0.0, 0.09])
    np.testing.assert_array_equal(held_sign(qd, 0.1), [0, 0, 0, 1, 1, 0, -1, -1])


def test_signals_take_the_smooth_sign_with_their_velocity():
    qd = np.array([-0.02, 0.0, 0.01])
    s = signals(None, qd, np.zeros(3), 0.01, shape=0.1)
    np.testing.assert_allclose(s.sign, np.tanh([-2.0, 0.0, 1.0]))
    assert (s.coulomb_velocity, s.shape, s.rigid, s.q) == (0.01, 0.1, None, None)
