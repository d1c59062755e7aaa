"""The epigraph form of the paper's criterion: its bounds' Jacobian against finite differences, and a
log cond restart that ends at a point where the extreme singular values are multiple (a kink, where
no gradient vanishes) and is Clarke-stationary there."""

import copy

import numpy as np
from conftest import UR5, write_config

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.search import nlp
from excite_cli.search.kkt import CONVERGED, extreme_clusters
from excite_cli.search.nlp import Epigraph, Evaluations
from excite_cli.search.sequence import run_sequence


def _small_ur5(tmp_path, objective: str):
    data = copy.deepcopy(UR5)
    data["trajectory"].update(harmonics=3, cost_samples=20, cost_period=0.4, constraint_period=0.05)
    data["optimizer"] = {"objective": objective, "max_iterations": 400, "seed": 1, "workers": 1}
    return build_excitation(load_problem(write_config(tmp_path, data)))


def test_the_bounds_jacobian_matches_finite_differences(tmp_path, monkeypatch):
    monkeypatch.setattr(nlp, "EPIGRAPH_BAND", np.inf)  # every bound's gradient, far ones too
    excitation = _small_ur5(tmp_path, "log_cond")
    criterion = excitation.criterion()
    alpha = excitation.random_start(np.random.default_rng(2))
    evaluations = Evaluations(criterion, excitation.constraints, excitation.boundary, criterion.value(alpha))
    epigraph = Epigraph(evaluations)
    z = excitation.boundary.to_variables(alpha)
    w = epigraph.start(z)
    sigma = criterion.singular_values(alpha)
    assert np.allclose(w[-2:], np.log([sigma[-1], sigma[0]]))  # t_max, t_min at the extremes
    assert np.isclose(epigraph.value(w), criterion.value(alpha), rtol=1e-9)  # log cond
    w = w + np.r_[np.zeros(z.size), 0.1, -0.1]  # the bounds off their extremes
    jacobian = epigraph.constraint_jacobian(w)
    step = 1e-6
    for k in range(w.size):
        e = np.zeros(w.size)
        e[k] = step
        fd = (epigraph.constraint_values(w + e) - epigraph.constraint_values(w - e)) / (2 * step)
        assert np.allclose(jacobian[:, k], fd, rtol=1e-5, atol=1e-6 * np.abs(jacobian).max()), k
    values = epigraph.constraint_values(w)
    assert values[-nlp.EPIGRAPH_SIZE * 2 :].max() < 0.0  # t_max above log σ_max, t_min below log σ_min


def test_a_log_cond_restart_ends_clarke_stationary_at_a_kink(tmp_path):
    """At its end point the largest and smallest singular values are multiple, the smooth KKT
    residual there stays far above the tolerance (no gradient of one eigenbasis vanishes), and
    Clarke's measure meets it: the restart converged at the non-smooth optimum. (One iteration as
    optimize runs it: its process holds one BLAS thread, so the solver's path is the same anywhere.)"""
    excitation = _small_ur5(tmp_path, "log_cond")
    excitation.spec.optimizer.restarts = 1
    tolerance = excitation.spec.optimizer.optimality_tolerance
    criterion = excitation.criterion()
    iteration = run_sequence(excitation, 1, seed=1)[0]
    result = next(r for r in iteration.restarts if r.index == iteration.kept)
    assert result.succeeded and result.stop == CONVERGED and result.optimality.residual <= tolerance
    clusters = extreme_clusters(criterion.singular_values(result.alpha), (1.0, -1.0))
    assert max(len(indices) for indices, _ in clusters) >= 2
    evaluations = Evaluations(criterion, excitation.constraints, excitation.boundary, result.objective)
    z = excitation.boundary.to_variables(result.alpha)
    assert evaluations.kkt(z, nonsmooth=False).residual > 10 * tolerance
    assert evaluations.kkt(z).residual <= tolerance


def test_the_next_singular_value_beyond_each_cluster_has_its_gradient(tmp_path):
    """With the band as shipped, the bounds of the singular values within it of their extreme and of
    the next one beyond them on each side carry their gradients (against central differences: the
    first a step raising the cluster would bring into it); the rows farther out are zero."""
    excitation = _small_ur5(tmp_path, "log_cond")
    criterion = excitation.criterion()
    alpha = excitation.random_start(np.random.default_rng(2))
    epigraph = Epigraph(Evaluations(criterion, excitation.constraints, excitation.boundary, criterion.value(alpha)))
    z = excitation.boundary.to_variables(alpha)
    w = epigraph.start(z)
    logs = np.log(criterion.singular_values(alpha))
    count = nlp.EPIGRAPH_SIZE
    bounds = epigraph.constraint_jacobian(w)[-2 * count :, : z.size].reshape(2, count, z.size)
    for side, order in enumerate((logs[::-1][:count], logs[:count])):
        reach = int(np.sum(np.abs(order - order[0]) <= nlp.EPIGRAPH_BAND)) + 1
        assert reach < count  # a random start: the band does not hold every bound
        for k in range(count):
            if k >= reach:
                assert not bounds[side, k].any(), (side, k)
                continue
            index = logs.size - 1 - k if side == 0 else k
            sign = 1.0 if side == 0 else -1.0

            def log_sigma(y, index=index):
                return np.log(criterion.singular_values(excitation.boundary.to_alpha(y))[index])

            fd = np.array([(log_sigma(z + 1e-6 * e) - log_sigma(z - 1e-6 * e)) / 2e-6 for e in np.eye(z.size)])
            assert np.allclose(bounds[side, k], sign * fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max()), (side, k)
