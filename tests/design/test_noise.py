"""The torque noise a design is for: each row weighs σ̄/√(σ_j² + ρ_j² τ_j(t)²) with τ pinocchio's
inverse dynamics of the URDF at the motion, the criterion's gradient (through the weights too)
against finite differences, and the noise section's bad values named."""

import re

import numpy as np
import pinocchio as pin
import pytest
from conftest import small

from excite_cli.config import NoiseConfig
from excite_cli.design.noise import HEDGE_FLOOR, TYPICAL_SEEDS, typical_torques
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import finite_difference_gradient
from excite_cli.errors import ExciteError
from excite_cli.search.sequence import describe, stacked_regressors
from excite_cli.storage.results import read_iterations, write_result


def _alpha(excitation, seed):
    return excitation.limits.random_start(excitation.trajectory.n_coefficients, np.random.default_rng(seed), 0.7)


def test_each_row_weighs_by_its_noise_at_the_torque_of_the_motion(panda_problem):
    problem = small(panda_problem)
    joints = problem.robot.active_joints
    problem.noise = NoiseConfig(absolute={joints[0]: 0.2, **{j: 0.05 for j in joints[1:]}}, relative=0.02)
    excitation = build_excitation(problem)
    alpha = _alpha(excitation, 3)
    weighted = excitation.criterion().regressor(alpha)
    plain = excitation.criterion(weighed=False).regressor(alpha)
    robot, (Q, QD, QDD) = excitation.robot, excitation.cost_basis.evaluate(alpha)
    tau = np.array([robot.torques(q, qd, qdd) for q, qd, qdd in zip(Q, QD, QDD)])  # pinocchio's RNEA
    sigma = np.array([0.2] + [0.05] * (len(joints) - 1))
    scale = np.exp(np.log(sigma).mean())  # σ̄: the geometric mean
    expected = scale / np.sqrt(sigma**2 + 0.02**2 * tau**2)  # (T, n)
    np.testing.assert_allclose(weighted, plain * expected.reshape(-1, 1), rtol=1e-9, atol=1e-12)
    assert expected.min() < 0.5 * expected.max()  # the weights do move with the torque


def test_equal_absolute_noise_is_the_unweighted_design(panda_problem):
    problem = small(panda_problem)
    alpha = _alpha(build_excitation(problem), 1)
    plain = build_excitation(problem).criterion(weighed=False)
    problem.noise = NoiseConfig(absolute=0.1, relative=0.0)  # the shipped configs' declaration
    noisy = build_excitation(problem).criterion()
    # to the bit (a weight 1 ± 1 ulp would move an optimizer's path over hundreds of iterations)
    np.testing.assert_array_equal(noisy.regressor(alpha), plain.regressor(alpha))
    assert noisy.value(alpha) == plain.value(alpha)
    np.testing.assert_array_equal(noisy.value_and_gradient(alpha)[1], plain.value_and_gradient(alpha)[1])


@pytest.mark.parametrize(
    "name, objective",
    [("panda_problem", "log_det"), ("panda_problem", "log_trace_inverse"), ("g1_problem", "log_cond")],
)
def test_gradient_through_weights_that_move_with_the_torque_matches_finite_differences(name, objective, request):
    problem = small(request.getfixturevalue(name))
    problem.optimizer.objective = objective
    problem.noise = NoiseConfig(absolute=0.05, relative=0.05)
    excitation = build_excitation(problem)
    criterion, alpha = excitation.criterion(), _alpha(excitation, 5)
    _, analytic = criterion.value_and_gradient(alpha)
    fd = finite_difference_gradient(criterion, alpha, step=1e-6, central=True)
    assert np.linalg.norm(analytic - fd) / np.linalg.norm(fd) < 1e-6
    problem.noise = NoiseConfig(absolute=0.05, relative=0.0)  # the weights' own term matters
    _, fixed = build_excitation(problem).criterion().value_and_gradient(alpha)
    assert np.linalg.norm(fixed - fd) / np.linalg.norm(fd) > 1e-3


@pytest.mark.parametrize(
    "noise, expected",
    [
        ({"absolute": {"elbow": 0.1}}, "noise.absolute: 'elbow' is not an active joint"),
        (  # noise given for one joint: the others are named, not called a limit of NaN
            {"absolute": {"panda_joint1": 0.1}},
            "noise.absolute: joint 'panda_joint2' needs a positive finite noise [Nm] (none given for it",
        ),
    ],
)
def test_a_noise_that_cannot_be_is_named(panda_problem, noise, expected):
    problem = small(panda_problem)
    problem.noise = NoiseConfig(**noise)
    with pytest.raises(ExciteError) as raised:
        build_excitation(problem)
    assert raised.value.describe().startswith(expected)


@pytest.mark.parametrize(
    "noise, expected",
    [
        ({"absolute": 1e300}, "absolute: 1e+300 is out of range; expected 1e-09 to 1e+06 Nm"),
        ({"absolute": 1e-300}, "absolute: 1e-300 is out of range"),
        ({"absolute": 0.0}, "absolute: 0 is out of range"),
        ({"relative": 1e300}, "relative: 1e+300 is out of range; expected 0 to 10"),
        ({"relative": -0.1}, "relative: -0.1 is out of range"),
        ({"relative": {"panda_joint2": 20.0}}, "relative: 20 for joint 'panda_joint2' is out of range"),
    ],
)
def test_a_noise_out_of_range_is_refused_where_it_is_read(noise, expected):
    """A number no sensor has (its weights' squares would overflow: numpy's warnings, then a traceback)."""
    with pytest.raises(ValueError, match=re.escape(expected)):
        NoiseConfig(**noise)


def test_a_joints_typical_torque_is_its_rms_torque_over_random_feasible_motions(panda_problem):
    excitation = build_excitation(small(panda_problem))
    model = excitation.robot.model
    data = model.createData()
    torques = []
    for seed in TYPICAL_SEEDS:
        Q, QD, QDD = excitation.cost_basis.evaluate(excitation.random_start(np.random.default_rng(seed)))
        torques += [pin.rnea(model, data, q, qd, qdd) for q, qd, qdd in zip(Q, QD, QDD)]  # the Panda: every joint
    expected = np.sqrt(np.mean(np.square(torques), axis=0))[: excitation.robot.n_joints]
    assert np.all(expected > 1e-3)  # every joint moves
    np.testing.assert_allclose(typical_torques(excitation), expected, rtol=1e-12)


def test_table_i_reports_the_rows_as_they_are_and_the_design_stacks_them_weighed(panda_problem, tmp_path):
    """cond(C) is the paper's (every row as it is) also where the design weighs the rows; the next
    iteration's C₀ is the weighed rows, and a resumed result reads the same figures back."""
    problem = small(panda_problem)
    joints = problem.robot.active_joints
    problem.noise = NoiseConfig(absolute={joints[0]: 0.2, **{j: 0.05 for j in joints[1:]}}, relative=0.02)
    excitation = build_excitation(problem)
    alphas = [_alpha(excitation, seed) for seed in (3, 4)]
    none = np.zeros((0, excitation.columns))
    first = describe(excitation, 1, alphas[0], none)
    second = describe(excitation, 2, alphas[1], none, earlier=[first])
    plain = [excitation.criterion(weighed=False).regressor(a) for a in alphas]
    assert first.cond_own == pytest.approx(np.linalg.cond(plain[0]), rel=1e-9)
    assert second.cond_own == pytest.approx(np.linalg.cond(plain[1]), rel=1e-9)
    assert second.cond_stacked == pytest.approx(np.linalg.cond(np.vstack(plain)), rel=1e-9)
    weighed = excitation.criterion().regressor(alphas[0])
    assert np.linalg.cond(weighed) > 1.5 * np.linalg.cond(plain[0])  # the weights change what cond reads
    np.testing.assert_array_equal(stacked_regressors(excitation, None, [first]), weighed)
    write_result(tmp_path / "r.h5", excitation, [first, second], 0)
    again = read_iterations(tmp_path / "r.h5", excitation)
    assert [r.cond_stacked for r in again] == [first.cond_stacked, second.cond_stacked]
    np.testing.assert_array_equal(again[0].design_rows, weighed)


def test_nothing_declared_weighs_each_row_by_the_hedge_over_half_the_joints_typical_torque(panda_problem):
    """No ``noise``: each row weighs as noise √((K R_j)² + τ_j(t)²), K = 0.5, R_j the joint's RMS torque
    (pinocchio's RNEA) over the random feasible motions of TYPICAL_SEEDS at the cost samples."""
    problem = small(panda_problem)
    problem.noise = None  # nothing declared
    excitation = build_excitation(problem)
    assert excitation.spec.hedged and "0.5 × each joint's typical torque" in excitation.noise.words
    robot, basis = excitation.robot, excitation.cost_basis
    tau = [
        pin.rnea(robot.model, robot.model.createData(), q, qd, qdd)
        for seed in TYPICAL_SEEDS
        for q, qd, qdd in zip(*basis.evaluate(excitation.random_start(np.random.default_rng(seed))))
    ]
    floor = HEDGE_FLOOR * np.sqrt(np.mean(np.square(tau), axis=0))
    alpha = _alpha(excitation, 2)
    Q, QD, QDD = basis.evaluate(alpha)
    now = np.array([pin.rnea(robot.model, robot.model.createData(), *x) for x in zip(Q, QD, QDD)])
    weights = np.exp(np.log(floor).mean()) / np.sqrt(floor**2 + now**2)
    plain = excitation.criterion(weighed=False).regressor(alpha)
    np.testing.assert_allclose(excitation.criterion().regressor(alpha), plain * weights.reshape(-1, 1), rtol=1e-9)
    problem.noise = NoiseConfig(absolute=0.1)  # the opt-out: every row the same, the paper's criterion
    equal = build_excitation(problem)
    assert not equal.spec.hedged
    np.testing.assert_allclose(equal.criterion().regressor(alpha), plain, rtol=1e-12)
    problem.noise, problem.optimizer.objective = None, "log_cond"  # the paper's cond: the rows as they are
    paper = build_excitation(problem)
    assert not paper.spec.hedged
    np.testing.assert_allclose(paper.criterion().regressor(alpha), plain, rtol=1e-12)
