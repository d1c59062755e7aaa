"""Pieces checked against closed forms: weighted least squares with its standard deviations, the CoM
polygon region, the units stored in the HDF5 result, and the random pool's counts."""

import h5py
import numpy as np
from conftest import CONFIGS, UR5, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.constraints.com_region import ComRegion
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import least_squares
from excite_cli.identification.fitting.normal import NormalEquations
from excite_cli.optimization.engine import Engine
from excite_cli.optimization.excitation import build_excitation
from excite_cli.optimization.random_baseline import DrawTask, draw_pool
from excite_cli.optimization.verify import constraint_jacobian_error


def test_weighted_least_squares_and_standard_deviations_match_the_closed_form():
    rng = np.random.default_rng(0)
    N, n, b = 400, 2, 3
    Y = rng.standard_normal((N * n, b))
    x_true = np.array([1.0, -2.0, 0.5])
    sigma = np.array([0.1, 0.4])  # per joint
    tau = Y @ x_true + rng.standard_normal(N * n) * np.tile(sigma, N)
    data = Dataset(Y, tau, np.arange(N) * 0.01, np.zeros(N, dtype=int), {})
    weights = 1.0 / sigma
    fit = least_squares(NormalEquations(data, []), [], weights)
    W = np.tile(weights, N)
    A, y = W[:, None] * Y, W * tau
    x = np.linalg.solve(A.T @ A, A.T @ y)
    s2 = np.sum((y - A @ x) ** 2) / (N * n - b)
    np.testing.assert_allclose(fit.x, x, rtol=1e-10)
    np.testing.assert_allclose(fit.std, np.sqrt(s2 * np.diag(np.linalg.inv(A.T @ A))), rtol=1e-8)


def test_com_polygon_region():
    excitation = build_excitation(load_problem(CONFIGS / "panda_joint_limits.yaml"))
    robot = excitation.robot
    com = robot.com(excitation.home)[0][:2]
    square = lambda half: com + half * np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]])  # noqa: E731
    alpha = excitation.limits.random_start(
        excitation.trajectory.n_coefficients, np.random.default_rng(1), 0.5, excitation.home
    )
    excursion = np.abs(np.array([robot.com(q)[0][:2] for q in excitation.grid_basis.evaluate(alpha)[0]]) - com).max()
    wide = ComRegion(robot, excitation.grid_basis, com, polygon=square(2.0 * excursion))
    narrow = ComRegion(robot, excitation.grid_basis, com, polygon=square(0.5 * excursion))
    assert (
        wide.check(alpha, excitation.grid_basis).max_violation
        < 0
        < narrow.check(alpha, excitation.grid_basis).max_violation
    )
    assert constraint_jacobian_error(narrow, alpha) < 1e-6


def test_result_datasets_carry_their_units(tmp_path):
    data = {
        **UR5,
        "trajectory": {**UR5["trajectory"], "harmonics": 3, "cost_samples": 20, "cost_period": 0.4},
        "optimizer": {"max_iterations": 5, "restarts": 1},
        "sequence": {"iterations": 1},
    }
    out = tmp_path / "u.h5"
    assert CliRunner().invoke(app, ["optimize", str(write_config(tmp_path, data)), "-o", str(out)]).exit_code == 0
    with h5py.File(out) as f:
        units = {name: f["iterations/1"][name].attrs["unit"] for name in ("alpha", "time", "q", "qd", "qdd")}
    assert units == {"alpha": "rad", "time": "s", "q": "rad", "qd": "rad/s", "qdd": "rad/s^2"}


def test_random_pool_counts():
    excitation = build_excitation(load_problem(CONFIGS / "smoke.yaml"))
    with Engine(excitation) as engine:
        pool = draw_pool(engine, 45, seed=3)
    assert len(pool.alphas) == 45 and pool.drawn >= 45 and pool.regressors.shape[0] == 45  # 3 tasks: 20 + 20 + 5
    alphas, regressors, drawn = DrawTask(0, 3, 10**9, budget_s=0.0)(excitation)
    assert alphas.shape[0] == regressors.shape[0] == drawn == 0  # no time, no draw
