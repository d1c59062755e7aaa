"""The one effect catalogue: the derivatives a design's gradient takes are those of the columns
identification fits (central differences), and what a design holds depends on the motion alone."""

import numpy as np
import pytest

from excite_cli.effects.catalogue import DESIGNED, EFFECTS
from excite_cli.effects.record import signals


@pytest.mark.parametrize("name", DESIGNED)
def test_a_designed_effects_slopes_are_the_derivatives_of_its_column(name):
    """(∂f/∂q̇, ∂f/∂q̈) of the record against central differences of its column, with no q given
    (a design's columns depend on q̇ and q̈ alone)."""
    rng = np.random.default_rng(3)
    qd, qdd, v_c, h = rng.normal(0.0, 0.02, 40), rng.normal(0.0, 1.0, 40), 0.01, 1e-7
    effect = EFFECTS[name]
    d_velocity, d_acceleration = effect.slopes(signals(None, qd, qdd, v_c))

    def column(qd, qdd):
        return effect.columns(signals(None, qd, qdd, v_c))[0]

    fd_velocity = (column(qd + h, qdd) - column(qd - h, qdd)) / (2 * h)
    fd_acceleration = (column(qd, qdd + h) - column(qd, qdd - h)) / (2 * h)
    np.testing.assert_allclose(d_velocity, fd_velocity, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(d_acceleration, fd_acceleration, rtol=1e-6, atol=1e-6)


def test_the_design_holds_the_effects_linear_in_the_motion_alone():
    """Friction, armature and the offset are designed; position, shaped, history and two-stage
    effects, and the motor (designed through its parts), are not."""
    assert set(DESIGNED) == {"coulomb", "viscous", "armature", "offset"}
    for effect in EFFECTS.values():
        if effect.designed:
            assert not (effect.position or effect.shape or effect.two_stage or effect.parts)


def test_a_motor_is_its_rotor_inertia_coulomb_and_viscous_friction_in_order():
    """The motor's columns on one motor coordinate are the armature's, Coulomb's and viscous
    friction's columns there: q̈, tanh(q̇/v_c), q̇."""
    rng = np.random.default_rng(4)
    qd, qdd = rng.normal(size=10), rng.normal(size=10)
    s = signals(None, qd, qdd, 0.05)
    motor = EFFECTS["motor"]
    assert motor.parts == ("armature", "coulomb", "viscous") and motor.coefficients == ("Ia", "Fc", "Fv")
    expected = [qdd, np.tanh(qd / 0.05), qd]
    for got, want in zip(motor.columns(s), expected, strict=True):
        np.testing.assert_array_equal(got, want)
