"""The smoothing of a criterion of the extreme singular values: its gradient against central
differences, its distance to the criterion against the bound (log-sum-exp's), and a restart that
stalled in epigraph form continued on it to Clarke stationarity."""

import copy
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import UR5, write_config

from excite_cli.config_file import load_problem
from excite_cli.constraints import accepted
from excite_cli.design.resolve import build_excitation
from excite_cli.search.engine import Engine
from excite_cli.search.kkt import CONVERGED, STALLED
from excite_cli.search.nlp import Evaluations
from excite_cli.search.optimizer import RestartResult
from excite_cli.search.restarts import RestartContext, _smoothed_round
from excite_cli.search.smoothing import Smoothed, log_criterion, smoothing_bound

HERE = Path(__file__).parent


def _small_ur5(tmp_path, objective: str):
    data = copy.deepcopy(UR5)
    data["trajectory"].update(harmonics=3, cost_samples=20, cost_period=0.4, constraint_period=0.05)
    data["optimizer"] = {"objective": objective, "seed": 1, "workers": 1}
    data["noise"] = {"absolute": 0.1}  # every row the same: the paper's cond and σ_min
    return build_excitation(load_problem(write_config(tmp_path, data)))


@pytest.mark.parametrize("objective", ["cond", "sigma_min"])
def test_the_smoothing_s_gradient_matches_central_differences(tmp_path, objective):
    """With μ wide enough that several singular values weigh at each extreme."""
    excitation = _small_ur5(tmp_path, objective)
    criterion = excitation.criterion()
    alpha = excitation.random_start(np.random.default_rng(3))
    smoothed = Smoothed(Evaluations(criterion, excitation.constraints, excitation.boundary, 0.0), mu=0.05)
    z = excitation.boundary.to_variables(alpha)
    logs = np.log(criterion.singular_values(alpha))
    assert max(np.sum(logs <= logs[0] + 0.1), np.sum(logs >= logs[-1] - 0.1)) >= 2  # more than one weighs
    gradient, step = smoothed.gradient(z), 1e-6
    fd = np.array([(smoothed.value(z + step * e) - smoothed.value(z - step * e)) / (2 * step) for e in np.eye(z.size)])
    assert np.allclose(gradient, fd, rtol=1e-5, atol=1e-6 * np.abs(gradient).max())


@pytest.mark.parametrize("objective", ["cond", "log_cond", "sigma_min"])
def test_the_smoothing_lies_between_the_criterion_and_its_bound(tmp_path, objective):
    """f ≤ f_μ ≤ f + μ Σ|w_c| log |B_c| (log-sum-exp lies between the max and the max + μ log k),
    f the criterion in its log form, at random starts and for several μ."""
    excitation = _small_ur5(tmp_path, objective)
    criterion = excitation.criterion()
    problem = Evaluations(criterion, excitation.constraints, excitation.boundary, 0.0)
    for seed in range(3):
        alpha = excitation.random_start(np.random.default_rng(seed))
        z, f = excitation.boundary.to_variables(alpha), log_criterion(criterion, alpha)
        for mu in (1e-4, 1e-2, 0.1, 1.0):
            gap = Smoothed(problem, mu).value(z) - f
            assert -1e-12 <= gap <= smoothing_bound(criterion, alpha, mu) + 1e-12
        assert smoothing_bound(criterion, alpha, 1.0) > 0.0  # with μ = 1 some band holds several σ


def test_a_restart_that_stalled_in_epigraph_form_converges_on_the_smoothing():
    """The UR3 of ``excite init`` with E-optimality, seed 0: iteration 1's kept restart ended its
    polish rounds "stalled" at a Clarke residual of 1.5e-3 (its four smallest σ within 7e-5). Its
    smoothed round (what polish runs after them) ends where Clarke's test of the criterion itself (a
    semidefinite program, independent of the smoothing) meets the tolerance, every constraint
    accepts it on the fine grid, and the criterion is higher by no more than the smoothing's bound."""
    problem = load_problem(HERE / "ur3_sigma_min_stall.yaml")
    excitation = build_excitation(problem)
    criterion, tolerance = excitation.criterion(), problem.optimizer.optimality_tolerance
    stalled_alpha = np.loadtxt(HERE / "ur3_sigma_min_stall.txt")
    evaluations = Evaluations(criterion, excitation.constraints, excitation.boundary, 0.0)
    optimality = evaluations.optimality(stalled_alpha)
    assert optimality.residual > tolerance
    value = criterion.value(stalled_alpha)
    stalled = RestartResult(0, stalled_alpha, value, 1032, "", 0.0, value, optimality=optimality, stop=STALLED)
    stalled = RestartResult(**{**stalled.__dict__, "end": "projected", "scale": 0.1, "margins": (0.0,) * 4})
    with Engine(excitation, 1) as engine:
        context = RestartContext(excitation, engine, 1, 0, criterion.prior, time.perf_counter() + 600)
        polished = _smoothed_round(context, stalled)
    assert polished.stop == CONVERGED and "smoothing" in polished.message
    assert evaluations.optimality(polished.alpha).residual <= tolerance
    assert accepted(excitation.constraints, polished.alpha, excitation.fine_basis)
    rise = log_criterion(criterion, polished.alpha) - log_criterion(criterion, stalled_alpha)
    assert rise <= smoothing_bound(criterion, stalled_alpha)


def test_the_smoothing_is_finite_where_the_regressor_loses_rank(tmp_path):
    """Without motion (the start's constant terms only) the inertial columns vanish: the smoothing
    floors σ as the criterion does (RANK_FLOOR σ_max), so its value and gradient stay finite and
    within the bound of the criterion's own floored value."""
    excitation = _small_ur5(tmp_path, "log_cond")
    criterion = excitation.criterion()
    alpha = excitation.random_start(np.random.default_rng(0))
    alpha[:, 1:] = 0.0
    assert criterion.singular_values(alpha)[0] <= 1e-12 * criterion.singular_values(alpha)[-1]
    smoothed = Smoothed(Evaluations(criterion, excitation.constraints, excitation.boundary, 0.0))
    z = excitation.boundary.to_variables(alpha)
    assert np.isfinite(smoothed.value(z)) and np.isfinite(smoothed.gradient(z)).all()
    gap = smoothed.value(z) - log_criterion(criterion, alpha)
    assert -1e-9 <= gap <= smoothing_bound(criterion, alpha) + 1e-9
