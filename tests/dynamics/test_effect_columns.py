"""Effect columns beside the base regressor: their values against the friction and inertia formulas,
their chain rule against finite differences, the columns the rigid body already holds left out, and
the config's joints and motors checked by name."""

import numpy as np
import pytest
from conftest import CONFIGS

from excite_cli.config import EffectsConfig, MotorConfig
from excite_cli.config_file import load_problem
from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.effect_columns import effect_columns
from excite_cli.dynamics.robot import load_robot
from excite_cli.errors import ExciteError, ExciteWarning

JOINTS = ["a", "b", "c"]


def _columns(**effects):
    motors = effects.pop("motors", [])
    return effect_columns(EffectsConfig(joints=effects, motors=motors, coulomb_velocity=0.05), JOINTS, 3)


def test_columns_are_the_friction_armature_and_offset_terms_on_their_rows():
    cols = _columns(
        b=["coulomb", "viscous", "armature", "offset"], motors=[MotorConfig(joints=["b", "c"], transmission=[2.0, 1.0])]
    )
    rng = np.random.default_rng(0)
    QD, QDD = rng.standard_normal((5, 3)), rng.standard_normal((5, 3))
    Y = cols.columns(QD, QDD).reshape(5, 3, -1)
    assert cols.names[:4] == ("Fc_b", "Fv_b", "Ia_b", "tau0_b") and cols.names[4] == "Ia_motor_b+c"
    np.testing.assert_allclose(
        Y[:, 1, :4], np.column_stack([np.tanh(QD[:, 1] / 0.05), QD[:, 1], QDD[:, 1], np.ones(5)])
    )
    assert np.all(Y[:, [0, 2], :4] == 0.0)  # a joint's own effect acts on its own row only
    s_dd, s_d = 2.0 * QDD[:, 1] + QDD[:, 2], 2.0 * QD[:, 1] + QD[:, 2]  # motor coordinate s = 2 q_b + q_c
    np.testing.assert_allclose(Y[:, 1, 4:], 2.0 * np.column_stack([s_dd, np.tanh(s_d / 0.05), s_d]))
    np.testing.assert_allclose(Y[:, 2, 4:], np.column_stack([s_dd, np.tanh(s_d / 0.05), s_d]))


def test_chain_matches_finite_differences_of_a_function_of_the_columns():
    cols = _columns(
        **{"*": ["coulomb", "viscous", "armature", "offset"]},
        motors=[MotorConfig(joints=["a", "c"], transmission=[1.0, -1.0])],
    )
    rng = np.random.default_rng(1)
    QD, QDD = 0.2 * rng.standard_normal((6, 3)), rng.standard_normal((6, 3))
    W = rng.standard_normal((18, cols.count))

    def f(qd, qdd):  # a smooth function of Y_E, its derivative in Y_E is 2 Y_E ⊙ W
        return float(np.sum(W * cols.columns(qd, qdd) ** 2))

    dqd, dqdd = cols.chain(2.0 * W * cols.columns(QD, QDD), QD, QDD)
    h = 1e-6
    for analytic, which in ((dqd, 0), (dqdd, 1)):
        fd = np.zeros_like(QD)
        for index in np.ndindex(QD.shape):
            step = np.zeros_like(QD)
            step[index] = h
            args_plus = (QD + step, QDD) if which == 0 else (QD, QDD + step)
            args_minus = (QD - step, QDD) if which == 0 else (QD, QDD - step)
            fd[index] = (f(*args_plus) - f(*args_minus)) / (2 * h)
        assert np.abs(analytic - fd).max() <= 1e-6 * np.abs(fd).max()


def test_the_first_joints_armature_regroups_with_its_links_inertia_and_is_left_out():
    """On a fixed-base arm, joint 1's rotor inertia adds to its link's inertia about the same vertical
    axis (the same column q̈₁ on row 1): it cannot be told apart, so the design leaves it out and says so."""
    problem = load_problem(CONFIGS / "panda_joint_limits.yaml")
    robot = load_robot(problem.robot, problem.folder)
    base = compute_base_parameters(robot)
    cols = effect_columns(EffectsConfig(joints={"*": ["armature", "viscous"]}), robot.joint_names, robot.n_rows)
    Q, QD, QDD = robot.random_states(60, np.random.default_rng(0))
    with pytest.warns(ExciteWarning, match="Ia_panda_joint1"):
        kept = cols.beside(robot.regressor_stack(Q, QD, QDD)[:, base.independent], QD, QDD)
    assert "Ia_panda_joint1" not in kept.names and "Ia_panda_joint4" in kept.names
    assert all(f"Fv_{j}" in kept.names for j in robot.joint_names)


def test_unknown_joints_and_a_short_transmission_row_name_their_field():
    with pytest.raises(ExciteError, match=r"effects\.joints.*'elbow' is not an active joint"):
        _columns(elbow=["coulomb"])
    with pytest.raises(ExciteError, match=r"effects\.motors\[0\]\.transmission.*1 ratios for 2 joints"):
        _columns(motors=[MotorConfig(joints=["a", "b"], transmission=[1.0])])
    assert _columns() is None


def test_typical_magnitudes_put_an_effects_torque_at_the_limits_at_five_percent_of_the_effort():
    cols = _columns(a=["coulomb", "viscous", "armature"])
    m = cols.magnitudes(np.array([100.0, 0.0, 50.0]), np.array([2.0, 1.0, 1.0]), np.array([10.0, 1.0, 1.0]))
    np.testing.assert_allclose(m, [5.0, 5.0 / 2.0, 5.0 / 10.0])
