"""Analytic gradient of cond / log cond (Eqs. 17, 45-49) against central finite differences."""

import warnings

import numpy as np
import pytest
from conftest import small

from excite_cli.config import EffectsConfig, MotorConfig
from excite_cli.criteria import CRITERIA, NAMES
from excite_cli.design.criterion import Criterion, condition_number
from excite_cli.design.information import PriorInformation
from excite_cli.design.noise import RowNoise
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import check_gradient, finite_difference_gradient
from excite_cli.errors import ExciteWarning


def _feasible_alpha(excitation, seed=0):
    return excitation.limits.random_start(excitation.trajectory.n_coefficients, np.random.default_rng(seed), 0.7)


@pytest.mark.parametrize("name", ["g1_problem", "panda_problem", "ur5_problem"])
@pytest.mark.parametrize("objective", NAMES)
def test_gradient_matches_finite_differences(name, objective, request):
    problem = small(request.getfixturevalue(name))
    problem.optimizer.objective = objective
    excitation = build_excitation(problem)
    criterion = excitation.criterion()
    alpha = _feasible_alpha(excitation)
    _, analytic = criterion.value_and_gradient(alpha)
    fd = finite_difference_gradient(criterion, alpha, step=1e-6, central=True)
    assert np.linalg.norm(analytic - fd) / np.linalg.norm(fd) < 1e-6


@pytest.mark.parametrize("name", ["g1_problem", "ur5_problem"])
@pytest.mark.parametrize("objective", ["log_cond", "sigma_min", "log_trace_inverse"])
def test_gradient_of_the_scaled_criterion_matches_finite_differences(name, objective, request):
    problem = small(request.getfixturevalue(name))
    problem.optimizer.objective, problem.optimizer.scaling = objective, "urdf"
    excitation = build_excitation(problem)
    prior = excitation.criterion().regressor(_feasible_alpha(excitation, seed=4))
    criterion = excitation.criterion(prior)
    assert criterion.frame is not None
    check = check_gradient(criterion, _feasible_alpha(excitation, seed=7), repeats=1)
    assert check.error_central < 1e-6


def test_scaled_condition_number_is_that_of_the_scaled_standard_regressor_in_any_base(ur5_problem):
    # cond(C L) = ratio of the extreme nonzero singular values of Y D, Y the standard regressor
    # (independent of any base) and D the URDF's parameter magnitudes; another base (C T, T⁻¹K)
    # gives the same value, while the paper's cond(C) changes.
    import dataclasses

    from excite_cli.design.information import parameter_magnitudes, scaled_frame

    excitation = build_excitation(small(ur5_problem))
    robot, base = excitation.robot, excitation.base
    Q, QD, QDD = excitation.cost_basis.evaluate(_feasible_alpha(excitation, 2))
    Y = robot.regressor_stack(Q, QD, QDD)
    d = parameter_magnitudes(robot)
    s = np.linalg.svd(Y * d, compute_uv=False)[: base.count]
    C = Y[:, base.independent]
    assert excitation.scaled_condition_number(C) == pytest.approx(s[0] / s[-1], rel=1e-8)
    T = np.eye(base.count) + 0.3 * np.random.default_rng(1).standard_normal((base.count, base.count))
    other = dataclasses.replace(base, regrouping=np.linalg.solve(T, base.regrouping))
    assert condition_number(C @ T @ scaled_frame(other, d)) == pytest.approx(s[0] / s[-1], rel=1e-8)
    assert abs(condition_number(C @ T) / condition_number(C) - 1) > 0.01


def test_gradient_with_prior_rows_and_base_wrench_rows(g1_problem):
    problem = small(g1_problem, harmonics=3, samples=15)
    problem.robot.base_wrench_rows = True
    excitation = build_excitation(problem)
    assert excitation.robot.n_rows == 6 + 14
    prior = excitation.criterion().regressor(_feasible_alpha(excitation, seed=5))
    criterion = excitation.criterion(prior)
    check = check_gradient(criterion, _feasible_alpha(excitation, seed=6), repeats=1)
    assert check.error_central < 1e-6


@pytest.mark.parametrize(
    "objective, expected",
    [
        ("sigma_min", lambda s: -np.log(s[-1])),
        ("log_det", lambda s: -np.sum(np.log(s**2)) / s.size),
    ],
)
def test_d_and_e_optimal_values(panda_problem, objective, expected):
    excitation = build_excitation(small(panda_problem))
    criterion = Criterion(excitation.robot, excitation.base, excitation.cost_basis, objective=CRITERIA[objective])
    alpha = _feasible_alpha(excitation, 3)
    s = np.linalg.svd(criterion.regressor(alpha), compute_uv=False)
    assert criterion.value(alpha) == pytest.approx(expected(s), rel=1e-12)
    assert criterion.value_and_gradient(alpha)[0] == pytest.approx(expected(s), rel=1e-9)


def test_value_is_the_condition_number_of_the_stacked_regressor(panda_problem):
    excitation = build_excitation(small(panda_problem))
    a, b = _feasible_alpha(excitation, 1), _feasible_alpha(excitation, 2)
    prior = excitation.criterion().regressor(a)
    criterion = Criterion(
        excitation.robot,
        excitation.base,
        excitation.cost_basis,
        prior=PriorInformation.of(prior),
        objective=CRITERIA["cond"],
    )
    stacked = np.vstack([prior, criterion.regressor(b)])
    s = np.linalg.svd(stacked, compute_uv=False)
    assert criterion.value(b) == pytest.approx(s[0] / s[-1], rel=1e-12)


def test_condition_number_is_infinite_at_rank_loss():
    C = np.zeros((5, 3))
    C[:, 0] = 1.0
    assert condition_number(C) == float("inf")
    assert condition_number(np.ones((2, 3))) == float("inf")


def test_gram_value_matches_the_svd_at_high_cond(panda_problem):
    """value_and_gradient takes σ from the eigenvalues of CᵀC (squared cond); value() from an SVD of C."""
    excitation = build_excitation(small(panda_problem))
    criterion = Criterion(excitation.robot, excitation.base, excitation.cost_basis, objective=CRITERIA["cond"])
    for scale, largest in ((1.0, 1e-12), (0.1, 1e-6), (0.01, None)):  # smaller motion, worse conditioned
        alpha = _feasible_alpha(excitation)
        alpha[:, 1:] *= scale
        exact = criterion.value(alpha)
        error = abs(criterion.value_and_gradient(alpha)[0] - exact) / exact
        assert error <= (largest or 1.0) and error <= np.finfo(float).eps * exact**2  # the Gram matrix squares cond
        # the solver's value: from the Gram matrix where cond(C) ≤ 10³, else the SVD's exactly
        solver = criterion.value(alpha, from_gram=True)
        assert solver == exact if exact > 1e3 else 0 < abs(solver - exact) / exact <= 1e-10
    assert exact > 1e8  # the last point is far worse than any optimizer iterate


def test_motionless_trajectory_gives_finite_value_and_gradient(panda_problem):
    # q constant: only gravity is excited, C loses rank, yet nothing is NaN.
    excitation = build_excitation(small(panda_problem))
    alpha = np.zeros((7, excitation.trajectory.n_coefficients))
    alpha[:, 0] = excitation.limits.centre[0]
    value, grad = excitation.criterion().value_and_gradient(alpha)
    assert np.isfinite(value) and value > np.log(1e8)
    assert np.all(np.isfinite(grad))


def test_gradient_with_a_prismatic_joint(panda_problem):
    """A moving prismatic joint (a finger): its axis moves the child's origin, not its orientation; the
    gradient still matches central differences."""
    problem = small(panda_problem, harmonics=3, samples=15)
    problem.robot.active_joints = [*problem.robot.active_joints[:3], "panda_finger_joint1"]
    problem.robot.locked_joints.pop("panda_finger_joint1", None)
    problem.robot.locked_joints["panda_finger_joint2"] = 0.0  # it mimics finger 1: held on purpose
    problem.limits.position_margin = 0.002
    excitation = build_excitation(problem)
    criterion = excitation.criterion(objective="log_cond")
    alpha = _feasible_alpha(excitation)
    _, analytic = criterion.value_and_gradient(alpha)
    assert (
        not excitation.robot.model.joints[excitation.robot.model.getJointId("panda_finger_joint1")]
        .shortname()
        .startswith("JointModelR")
    )
    fd = finite_difference_gradient(criterion, alpha, step=1e-7, central=True)
    assert np.linalg.norm(analytic - fd) / np.linalg.norm(fd) < 1e-6


@pytest.mark.end_to_end
@pytest.mark.parametrize("name", ["g1_problem", "ur5_problem"])
@pytest.mark.parametrize("objective, scaling", [("log_det", "none"), ("log_cond", "urdf"), ("sigma_min", "none")])
def test_gradient_with_effect_columns_matches_finite_differences(name, objective, scaling, request):
    """C = [Y_B | Y_E] with Coulomb (smooth sign), viscous, armature and offset columns on every joint and
    a coupled motor on the last two joints, stacked under a prior with the same columns."""
    problem = small(request.getfixturevalue(name))
    problem.optimizer.objective, problem.optimizer.scaling = objective, scaling
    last = problem.robot.active_joints[-2:]
    problem.effects = EffectsConfig(
        joints={"*": ["coulomb", "viscous", "armature", "offset"]},
        motors=[MotorConfig(joints=last, transmission=[1.0, 1.0])],
        coulomb_velocity=0.05,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExciteWarning)  # armatures that regroup with the rigid body
        excitation = build_excitation(problem)
    assert excitation.effects.count >= 3 * len(problem.robot.active_joints)
    prior = excitation.criterion().regressor(_feasible_alpha(excitation, seed=4))
    criterion = excitation.criterion(prior)
    assert prior.shape[1] == excitation.base.count + excitation.effects.count
    check = check_gradient(criterion, _feasible_alpha(excitation, seed=7), repeats=1)
    assert check.error_central < 1e-6


def test_excitation_level_with_effects_is_the_geometric_mean_singular_value_of_the_scaled_regressor(panda_problem):
    problem = small(panda_problem)
    problem.effects = EffectsConfig(joints={"*": ["coulomb", "viscous"]})
    excitation = build_excitation(problem)
    C = excitation.criterion().regressor(_feasible_alpha(excitation, 5))
    s = np.linalg.svd(C @ excitation.scaled_frame, compute_uv=False)
    assert C.shape[1] == excitation.base.count + 2 * len(problem.robot.active_joints)
    assert excitation.excitation_level(C) == pytest.approx(np.exp(np.log(s).mean()), rel=1e-9)
    assert excitation.scaled_condition_number(C) == pytest.approx(s[0] / s[-1], rel=1e-9)


def test_gradient_with_row_weights_matches_finite_differences(ur5_problem):
    """Rows weighted per joint (σ̄/σ_j of a measured prior, no part relative to the torque), stacked
    under a weighted prior, with effect columns."""
    problem = small(ur5_problem)
    problem.effects = EffectsConfig(joints={"*": ["coulomb", "viscous"]}, coulomb_velocity=0.05)
    excitation = build_excitation(problem)
    sigma = np.linspace(0.5, 2.0, excitation.robot.n_rows)
    noise = RowNoise(sigma, np.zeros_like(sigma), 1.0, excitation.robot.urdf_parameters())
    weights = 1.0 / sigma
    plain = excitation.criterion(weighed=False)
    prior = (
        plain.regressor(_feasible_alpha(excitation, seed=4))
        * np.tile(weights, problem.trajectory.cost_samples)[:, None]
    )
    criterion = Criterion(
        excitation.robot,
        excitation.base,
        excitation.cost_basis,
        CRITERIA["log_det"],
        PriorInformation.of(prior),
        effects=excitation.effects,
        noise=noise,
    )
    alpha = _feasible_alpha(excitation, seed=7)
    np.testing.assert_allclose(
        criterion.regressor(alpha), plain.regressor(alpha) * np.tile(weights, problem.trajectory.cost_samples)[:, None]
    )
    assert check_gradient(criterion, alpha, repeats=1).error_central < 1e-6
