"""The random baseline (ref. [16], Table II): greedy selection against brute force, and feasibility of
every selected candidate on the fine grid."""

import itertools

import h5py
import numpy as np
import pytest
import yaml
from conftest import CONFIGS, TESTS, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.search.engine import Engine
from excite_cli.search.random_baseline import DrawTask, draw_pool, greedy_selection, random_candidate

HERE = TESTS


def _cond(C):
    s = np.linalg.svd(C, compute_uv=False)
    return s[0] / s[-1]


def test_each_greedy_step_is_the_brute_force_best():
    rng = np.random.default_rng(0)
    regressors = rng.normal(size=(7, 12, 5)) * rng.uniform(0.1, 3.0, size=(7, 1, 5))
    chosen, conds = greedy_selection(regressors, 4)
    for step in range(4):
        before = [regressors[i] for i in chosen[:step]]
        options = {k: _cond(np.vstack(before + [regressors[k]])) for k in range(7) if k not in chosen[:step]}
        assert chosen[step] == min(options, key=options.get)
        assert conds[step] == pytest.approx(options[chosen[step]], rel=1e-8)
    assert len(set(chosen)) == 4


def test_greedy_first_step_and_pair_against_all_pairs():
    rng = np.random.default_rng(1)
    regressors = rng.normal(size=(6, 10, 4)) * rng.uniform(0.05, 2.0, size=(6, 1, 4))
    chosen, conds = greedy_selection(regressors, 2)
    assert conds[0] == pytest.approx(min(_cond(r) for r in regressors), rel=1e-8)
    best_pair = min(_cond(np.vstack([regressors[i], regressors[j]])) for i, j in itertools.combinations(range(6), 2))
    assert conds[1] >= best_pair - 1e-9  # greedy cannot beat the exhaustive optimum


def test_candidates_fill_the_limits_and_hold_the_constraints():
    excitation = build_excitation(load_problem(HERE / "panda_capsules.yaml"))
    rng = np.random.default_rng(2)
    for _ in range(5):
        alpha = random_candidate(excitation, rng)
        assert alpha is not None
        checks = [c.check(alpha, excitation.fine_basis) for c in excitation.constraints]
        assert all(ch.max_violation <= 0 for ch in checks)
        # something is at its bound: the joint limits (within the margin) or a capsule pair
        assert checks[0].max_violation > -0.05 or checks[1].max_violation > -0.5


def test_compare_random_command(tmp_path):
    data = yaml.safe_load((HERE / "panda_capsules.yaml").read_text())
    data.update(
        optimizer={"max_iterations": 30, "restarts": 1}, sequence={"iterations": 2}, output=str(tmp_path / "panda.h5")
    )
    config = write_config(tmp_path, data)
    result = CliRunner().invoke(app, ["compare-random", str(config), "--pool", "12"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "Table II" in result.output and "ratio" in result.output
    with h5py.File(tmp_path / "panda_random.h5") as f:
        assert f.attrs["method"] == "random_selection" and f.attrs["pool_size"] == 12
        assert list(f["table"]["iteration"]) == [1, 2]
        for k in ("1", "2"):
            assert f["iterations"][k].attrs["max_violation"] <= 0
        stacked = np.vstack([f["iterations/1/regressor"][()], f["iterations/2/regressor"][()]])
        assert f["table"]["cond_stacked"][1] == pytest.approx(_cond(stacked), rel=1e-9)
    assert (tmp_path / "panda_random_comparison.png").stat().st_size > 5000
    assert (tmp_path / "panda_optimized.h5").exists()


def test_random_pool_counts():
    excitation = build_excitation(load_problem(CONFIGS / "smoke.yaml"))
    with Engine(excitation) as engine:
        pool = draw_pool(engine, 45, seed=3)
    assert len(pool.alphas) == 45 and pool.drawn >= 45 and pool.regressors.shape[0] == 45  # 3 tasks: 20 + 20 + 5
    alphas, regressors, drawn = DrawTask(0, 3, 10**9, budget_s=0.0)(excitation)
    assert alphas.shape[0] == regressors.shape[0] == drawn == 0  # no time, no draw
