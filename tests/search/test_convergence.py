"""Convergence is measured, not assumed: the KKT residual against analytic cases, honest stop
reasons, restarts stored and printed, a restart reported as converged meets its tolerance
(recomputed here from the stored α with finite differences), and the projection onto the feasible
set that ends every restart."""

import copy
import time

import h5py
import numpy as np
import pytest
from conftest import UR5, write_config
from scipy.optimize import nnls
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config import NoiseConfig
from excite_cli.config_file import load_problem
from excite_cli.constraints import accepted
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import finite_difference_gradient
from excite_cli.search.feasible import project, repair
from excite_cli.search.kkt import (
    ACTIVE_TOLERANCE,
    CONVERGED,
    SOLVER_FAILED,
    STALLED,
    STILL_IMPROVING,
    TIME_BUDGET,
    Optimality,
    clarke_optimality,
    extreme_clusters,
    kkt_optimality,
    stop_reason,
)
from excite_cli.search.nlp import Evaluations

runner = CliRunner()


def test_kkt_residual_of_an_analytic_problem():
    # min x² + y² s.t. 1 − x ≤ 0: the optimum (1, 0) has λ = 2; at (1, 0.5) the y-gradient 1 is left
    at_optimum = kkt_optimality(np.array([2.0, 0.0]), np.array([0.0]), np.array([[-1.0, 0.0]]))
    assert at_optimum.residual == pytest.approx(0.0, abs=1e-12) and at_optimum.active == 1
    off = kkt_optimality(np.array([2.0, 1.0]), np.array([0.0]), np.array([[-1.0, 0.0]]))
    assert off.residual == pytest.approx(1.0 / 2.0)
    # the same point with the constraint far from its bound: nothing active, the whole gradient is left
    inactive = kkt_optimality(np.array([2.0, 0.0]), np.array([-1.0]), np.array([[-1.0, 0.0]]))
    assert inactive.active == 0 and inactive.residual == pytest.approx(1.0)
    # a multiplier of the wrong sign is not allowed: pushing into the constraint is not stationary
    wrong = kkt_optimality(np.array([-2.0, 0.0]), np.array([0.0]), np.array([[-1.0, 0.0]]))
    assert wrong.residual == pytest.approx(1.0)


def test_clarke_residual_of_an_analytic_nonsmooth_problem():
    """min λ_max([[x, y], [y, −x]]) + y/2 = √(x² + y²) + y/2, at (0, 0) where both eigenvalues are 0:
    h_11 = x, h_22 = −x, h_12 = y (plus the smooth y/2 on the diagonal, which a trace-1 S keeps).
    S = [[½, −¼], [−¼, ½]] ⪰ 0 gives 0; each eigenvalue's own gradient, (±1, ½), leaves 1 (KKT), and
    their convex combinations (S diagonal) leave ½. Off the kink, (1, 0), the cluster is one value."""
    cluster = np.array([[[1.0, 0.5], [0.0, 1.0]], [[0.0, 1.0], [-1.0, 0.5]]])
    none, no_jacobian = np.zeros(0), np.zeros((0, 2))
    at_kink = clarke_optimality([cluster], np.array([1.0, 0.5]), none, no_jacobian)
    assert at_kink.residual == pytest.approx(0.0, abs=1e-7)
    assert kkt_optimality(np.array([1.0, 0.5]), none, no_jacobian).residual == pytest.approx(1.0)
    diagonal = cluster * np.eye(2)[:, :, None]  # S diagonal only: (S11 − S22, ½)
    assert clarke_optimality([diagonal], np.array([1.0, 0.5]), none, no_jacobian).residual == pytest.approx(
        0.5, abs=1e-7
    )
    # with a constraint −y ≤ 0 active, ν takes the y part: 0 with the diagonal alone too
    jacobian = np.array([[0.0, -1.0]])
    assert clarke_optimality([diagonal], np.array([1.0, 0.5]), np.array([0.0]), jacobian).residual < 1e-7


def test_the_clusters_are_the_singular_values_near_an_extreme():
    sigma = np.array([1.0, 1.005, 1.5, 3.0, 9.95, 10.0])
    (top, w_top), (bottom, w_bottom) = extreme_clusters(sigma, (1.0, -1.0))
    assert top.tolist() == [5, 4] and bottom.tolist() == [0, 1] and (w_top, w_bottom) == (1.0, -1.0)
    assert [c[0].tolist() for c in extreme_clusters(sigma, (0.0, -1.0))] == [[0, 1]]  # E-optimality: σ_min


def test_a_clusters_gradients_match_finite_differences_with_its_eigenvectors_held(ur5_problem):
    """∇h_ab of h_ab = v_aᵀ CᵀC v_b / (2λ̄) with v held at α, against central differences of h_ab."""
    problem = copy.deepcopy(ur5_problem)
    problem.trajectory.harmonics, problem.trajectory.cost_samples = 3, 20
    excitation = build_excitation(problem)
    criterion = excitation.criterion(objective="log_cond", scaling="none")  # clusters are cond's, of C
    alpha = excitation.limits.random_start(excitation.trajectory.n_coefficients, np.random.default_rng(3), 0.7)
    indices = np.array([0, 1, 4])
    gradients = criterion.cluster_gradients(alpha, indices)
    C = criterion.regressor(alpha)
    eig, V = np.linalg.eigh(C.T @ C)
    V, mean = V[:, indices], eig[indices].mean()
    for a, b in [(0, 0), (0, 2), (1, 2)]:

        class Pair:  # h_ab with the eigenvectors of α, for the finite differences
            def value(self, x):
                rows = criterion.regressor(x)
                return float(V[:, a] @ rows.T @ rows @ V[:, b] / (2 * mean))

        fd = finite_difference_gradient(Pair(), alpha, step=1e-6, central=True)
        assert np.linalg.norm(gradients[a, b] - fd) / np.linalg.norm(fd) < 1e-6
    assert np.allclose(gradients[0, 2], gradients[2, 0])


def test_stop_reasons():
    near = Optimality(1e-5, 3, 1.0, 0.0)
    far = Optimality(0.3, 3, 1.0, 0.0)
    falling = list(np.linspace(10.0, 5.0, 50))
    flat = [10.0] * 20 + [5.0] * 30
    assert stop_reason(near, flat, limit=True, failed=True, tolerance=1e-3) == CONVERGED
    assert stop_reason(far, falling, limit=True, failed=False, tolerance=1e-3) == STILL_IMPROVING
    assert stop_reason(far, flat, limit=True, failed=False, tolerance=1e-3) == STALLED
    assert (
        stop_reason(far, falling, limit=False, failed=False, tolerance=1e-3) == STALLED
    )  # the solver's own test, not KKT
    assert stop_reason(far, falling, limit=False, failed=True, tolerance=1e-3) == SOLVER_FAILED
    assert stop_reason(far, falling, limit=True, failed=False, tolerance=1e-3, out_of_time=True) == TIME_BUDGET
    assert stop_reason(near, falling, limit=True, failed=False, tolerance=1e-3, out_of_time=True) == CONVERGED


def _small_problem(tmp_path, objective, iterations=2):
    data = copy.deepcopy(UR5)
    data["trajectory"].update(harmonics=3, cost_samples=20, cost_period=0.4, constraint_period=0.05)
    data["optimizer"] = {"objective": objective, "max_iterations": 300, "restarts": 2, "seed": 1, "workers": 1}
    data["sequence"] = {"iterations": iterations}
    data["noise"] = {"absolute": 0.1}  # every row the same: the rows the solvers' settings were tuned on
    return write_config(tmp_path, data)


def _fd_kkt(excitation, prior, alpha, step=1e-6):
    """The KKT residual of the optimality module, recomputed independently: the criterion's gradient
    in the optimizer's variables by central differences, the multipliers by NNLS."""
    boundary, criterion = excitation.boundary, excitation.criterion(prior)
    z = boundary.to_variables(alpha)
    gradient = np.array(
        [
            (criterion.value(boundary.to_alpha(z + step * e)) - criterion.value(boundary.to_alpha(z - step * e)))
            / (2 * step)
            for e in np.eye(z.size)
        ]
    )
    parts = [c.evaluate(boundary.to_alpha(z)) for c in excitation.constraints]
    values = np.concatenate([g for g, _ in parts])
    jacobian = boundary.chain(np.vstack([J for _, J in parts]))
    active = values >= -ACTIVE_TOLERANCE
    lam = nnls(jacobian[active].T, -gradient)[0]
    stationarity = np.abs(gradient + jacobian[active].T @ lam).max()
    complementarity = np.max(lam * np.abs(values[active]), initial=0.0)
    return max(stationarity, complementarity) / max(1.0, np.abs(gradient).max())


def test_a_restart_reported_converged_meets_its_tolerance(tmp_path):
    config = _small_problem(tmp_path, "log_det")
    out = tmp_path / "r.h5"
    run = runner.invoke(app, ["optimize", str(config), "-o", str(out)])
    assert run.exit_code == 0, run.output
    assert "Restarts" in run.output and "KKT residual" in run.output
    excitation = build_excitation(load_problem(config))
    tolerance = excitation.spec.optimizer.optimality_tolerance
    converged = 0
    with h5py.File(out) as f:
        prior = np.zeros((0, excitation.base.count))
        for k in sorted(f["iterations"], key=int):
            group = f["iterations"][k]
            restarts = group["restarts"]
            assert len(restarts) == 2 and group.attrs["stop"] == restarts[str(restarts.attrs["kept"])].attrs["stop"]
            for r in restarts.values():
                assert r["history"].shape == (r.attrs["iterations"], 2)
                if r.attrs["stop"] == CONVERGED:
                    converged += 1
                    assert _fd_kkt(excitation, prior, r["alpha"][()]) <= 1.01 * tolerance
                    assert r.attrs["kkt_residual"] <= tolerance
            prior = np.vstack([prior, excitation.criterion().regressor(group["alpha"][()])])  # as the design
    assert converged >= 1  # the smooth D-optimal criterion converges on this small problem


def test_a_restart_stops_where_it_meets_the_kkt_tolerance_or_its_time_limit(tmp_path):
    """With the solver's own test out of play (ftol 1e-14), a restart on the small problem stops at
    an iterate that meets the KKT tolerance, not at its 300 iterations; its end point meets the
    tolerance by central differences. With no time left it stops at the first iterate."""
    from excite_cli.search.restarts import RestartTask

    problem = load_problem(_small_problem(tmp_path, "log_det"))
    problem.optimizer.tolerance = 1e-14
    excitation = build_excitation(problem)
    prior = np.zeros((0, excitation.base.count))
    result = RestartTask(1, 0, 1, prior)(excitation)
    assert result.stop == CONVERGED and "StopIteration" in result.message
    assert result.iterations < 300
    assert _fd_kkt(excitation, prior, result.alpha) <= 1.01 * problem.optimizer.optimality_tolerance
    hurried = RestartTask(1, 0, 1, prior, time_limit=0.0)(excitation)
    assert hurried.iterations <= 2 and hurried.stop == TIME_BUDGET and hurried.succeeded


def test_the_kept_restart_continues_from_a_fresh_matrix_until_it_converges(tmp_path):
    """A restart stopped at 15 iterations short of the tolerance, polished in rounds of 40: each round
    starts at the end point of the one before (iterations and history joined), none ends higher, and
    the last converges, its KKT residual recomputed by central differences. A converged restart, or
    polish_rounds 0, is left as it is; one the deadline leaves unpolished says "time budget"."""
    from excite_cli.search.engine import Engine
    from excite_cli.search.restarts import RestartContext, RestartTask, polish

    problem = load_problem(_small_problem(tmp_path, "log_det"))
    opts = problem.optimizer
    opts.max_iterations, opts.polish_rounds = 15, 20
    excitation = build_excitation(problem)
    prior = np.zeros((0, excitation.base.count))
    first = RestartTask(1, 0, 1, prior)(excitation)
    assert first.succeeded and first.stop != CONVERGED and first.iterations == 15
    opts.max_iterations = 40  # rounds long enough to learn the curvature: each keeps the run's scale
    deadline = time.perf_counter() + 600.0
    with Engine(excitation) as serial:
        context = RestartContext(excitation, serial, 1, 1, prior, deadline)
        polished = polish(context, [first], 0)[0]
        assert polish(context, [polished], 0)[0] is polished
        late = polish(RestartContext(excitation, serial, 1, 1, prior, time.perf_counter() - 1.0), [first], 0)[0]
        assert late.stop == TIME_BUDGET and late.iterations == 15  # not polished: the budget decided
        opts.polish_rounds = 0
        assert polish(context, [first], 0)[0] is first
    assert polished.stop == CONVERGED and polished.objective < first.objective
    assert polished.iterations > 15 and polished.history.shape == (polished.iterations, 2)
    np.testing.assert_array_equal(polished.history[:15], first.history)
    assert polished.start_objective == first.start_objective and polished.index == 0
    assert _fd_kkt(excitation, prior, polished.alpha) <= 1.01 * opts.optimality_tolerance
    assert accepted(excitation.constraints, polished.alpha)


def test_projection_ends_inside_and_nearer_than_bisection(ur5_problem):
    excitation = build_excitation(ur5_problem)
    start = excitation.random_start(np.random.default_rng(3))
    outside = start.copy()
    outside[:, 1:] *= 3.0  # well beyond the limits
    outside = excitation.boundary.project(outside)
    assert not accepted(excitation.constraints, outside)
    criterion = excitation.criterion()
    problem = Evaluations(criterion, excitation.constraints, excitation.boundary, criterion.value(start))
    z = excitation.boundary.to_variables(outside)
    projected = project(problem, z)
    assert projected is not None and accepted(excitation.constraints, projected)
    bisected = repair(excitation.constraints, outside, start, excitation.boundary)
    distance = [np.linalg.norm(excitation.boundary.to_variables(a) - z) for a in (projected, bisected)]
    assert distance[0] < distance[1]


@pytest.mark.parametrize("method", ["SLSQP", "trust-constr", "ipopt"])
def test_every_method_ends_feasible_and_below_its_start(ur5_problem, method):
    if method == "ipopt":
        pytest.importorskip("cyipopt", reason="IPOPT not installed (Makefile target ipopt)")
    ur5_problem.optimizer.method = method
    ur5_problem.optimizer.objective = "log_det"  # the methods, on the criterion they were tuned on
    ur5_problem.noise = NoiseConfig(absolute=0.1)  # and its rows, every one the same
    ur5_problem.optimizer.max_iterations = 40
    excitation = build_excitation(ur5_problem)
    from excite_cli.search.restarts import RestartTask

    result = RestartTask(1, 0, 2, np.zeros((0, excitation.base.count)))(excitation)
    assert accepted(excitation.constraints, result.alpha)
    assert result.objective < result.start_objective - 0.5 and result.iterations > 0
    assert result.history.shape == (result.iterations, 2) and result.stop


def test_excitation_level_is_the_scaled_standard_regressor_and_does_not_depend_on_the_base(panda_problem):
    import dataclasses

    from excite_cli.design.information import excitation_level, parameter_magnitudes

    excitation = build_excitation(panda_problem)
    robot, base = excitation.robot, excitation.base
    alpha = excitation.random_start(np.random.default_rng(0))
    Q, QD, QDD = excitation.cost_basis.evaluate(alpha)
    Y = robot.regressor_stack(Q, QD, QDD)  # the standard regressor, independent of any base
    d = parameter_magnitudes(robot)
    truth = np.exp(np.log(np.linalg.svd(Y * d, compute_uv=False)[: base.count]).mean())
    C = Y[:, base.independent]
    assert excitation_level(C, base, d) == pytest.approx(truth, rel=1e-8)
    T = np.eye(base.count) + 0.3 * np.random.default_rng(1).standard_normal((base.count, base.count))
    other = dataclasses.replace(base, regrouping=np.linalg.solve(T, base.regrouping))
    assert excitation_level(C @ T, other, d) == pytest.approx(truth, rel=1e-8)
    assert excitation_level(C[:, :-1] @ np.ones((base.count - 1, base.count)), base, d) == 0.0  # rank-deficient


def test_screening_continues_the_best_starts_wherever_they_run(ur5_problem):
    from excite_cli.search.engine import Engine
    from excite_cli.search.restarts import RestartContext, run_restarts

    opts = ur5_problem.optimizer
    opts.restarts, opts.starts, opts.screen_iterations, opts.max_iterations = 2, 5, 8, 30
    excitation = build_excitation(ur5_problem)
    prior = np.zeros((0, excitation.base.count))
    with Engine(excitation) as serial:
        runs = run_restarts(RestartContext.starting(excitation, serial, 1, 3, prior))
    with Engine(excitation, workers=2) as pool:
        again = run_restarts(RestartContext.starting(excitation, pool, 1, 3, prior))
    assert [r.alpha.tobytes() for r in runs] == [r.alpha.tobytes() for r in again]
    assert [r.index for r in runs] == list(range(5))
    out = [r for r in runs if r.stop == "screened out"]
    kept = [r for r in runs if r.stop != "screened out"]
    assert len(out) == 3 and len(kept) == 2
    assert all(r.iterations == 8 for r in out) and all(8 < r.iterations <= 30 for r in kept)
    assert all(r.history.shape == (r.iterations, 2) for r in runs)
    # the continued ones were the best two of the screening, and continuing never makes a point worse
    assert max(r.objective for r in kept) <= min(r.objective for r in out)
    assert all(accepted(excitation.constraints, r.alpha) for r in runs)


def test_a_failed_restart_is_never_kept_when_another_succeeded():
    """The lowest end value of a restart that failed, or that ended at its start or a bisection
    towards it, loses to any restart whose solver gave its own end point."""
    from excite_cli.search.optimizer import RestartResult, best_restart

    def restart(index, objective, stop, end):
        return RestartResult(index, np.zeros((1, 3)), objective, 10, "", 0.0, stop=stop, end=end)

    failed = restart(0, -9.0, SOLVER_FAILED, "projected")
    at_start = restart(1, -8.0, STALLED, "start")
    towards_start = restart(2, -7.5, STALLED, "bisection")
    solved = restart(3, -6.0, STALLED, "projected")
    better = restart(4, -6.5, CONVERGED, "inside")
    assert best_restart([failed, at_start, towards_start, solved]) is solved
    assert best_restart([failed, at_start, towards_start, solved, better]) is better
    assert not any(r.succeeded for r in (failed, at_start, towards_start))
    assert best_restart([failed, at_start]) is failed  # a result written before the rule: the lowest


@pytest.mark.end_to_end
def test_when_every_restart_fails_more_starts_run_then_the_run_stops(ur5_problem):
    """95 % of every joint's torque is out of reach at the UR5's limits: every restart ends
    infeasible. More starts run, each from its own seed, until the time budget is spent; then the
    sequence stops with NoSolution (exit 1 on the command line) instead of keeping a start."""
    from excite_cli.errors import NoSolution
    from excite_cli.search.engine import Engine
    from excite_cli.search.restarts import RestartContext, run_restarts
    from excite_cli.search.sequence import run_sequence

    ur5_problem.limits.torque, ur5_problem.limits.min_torque_use = "urdf", 0.95
    opts = ur5_problem.optimizer
    opts.restarts, opts.max_iterations, opts.time_budget = 1, 3, 8.0  # a restart: 2-4 s
    excitation = build_excitation(ur5_problem)
    with Engine(excitation) as serial:
        runs = run_restarts(RestartContext.starting(excitation, serial, 1, 0, np.zeros((0, excitation.base.count))))
        assert len(runs) >= 2 and [r.index for r in runs] == list(range(len(runs)))
        assert not any(r.succeeded for r in runs) and {r.stop for r in runs} == {"infeasible"}
        assert len({r.start_objective for r in runs}) == len(runs)  # each from a start of its own
        with pytest.raises(NoSolution, match="iteration 1: none of") as raised:
            run_sequence(excitation, 2, 0, engine=serial)
    assert raised.value.status == 1
    opts.starts, opts.screen_iterations, opts.time_budget = 2, 2, 0.001  # screened, none to continue
    with Engine(excitation, workers=2) as pool:
        screened = run_restarts(RestartContext.starting(excitation, pool, 1, 0, np.zeros((0, excitation.base.count))))
    assert [r.index for r in screened] == [0, 1] and not any(r.succeeded for r in screened)
