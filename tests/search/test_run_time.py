"""The run time ``check`` estimates and ``init`` sizes by: the solver iterations a sequential iteration
spends on its busiest worker, counted by hand from the restarts' rules; the sizes that fit a budget;
and the measured times of a problem (real solver iterations: positive, every piece named)."""

import numpy as np
import pytest
from conftest import CONFIGS

from excite_cli.config import OptimizerConfig
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.search.run_time import SIZES, Timing, measure, rounds, sequence_seconds, sizes_within


def _options(**fields) -> OptimizerConfig:
    return OptimizerConfig(**fields)


def test_the_busiest_worker_counts_the_screened_starts_the_restarts_and_the_polish_in_rounds():
    """16 starts screened for 40 on 2 workers: 8 rounds of 40; 4 restarts run on to 400: 2 rounds of 360;
    one polish round of 400 on one worker: 320 + 720 + 400 iterations, 8 + 2 + 1 runs."""
    options = _options(starts=16, restarts=4, max_iterations=400, screen_iterations=40)
    assert rounds(options, 2, 1) == (1440, 11)
    assert rounds(options, 3, 0) == (6 * 40 + 2 * 360, 8)  # 16/3 and 4/3 rounded up
    alone = _options(restarts=3, max_iterations=100)  # no screening: every restart to its limit
    assert rounds(alone, 2, 2) == (2 * 100 + 2 * 100, 4)


def test_the_sequence_takes_its_iterations_times_a_timed_iteration_and_run():
    """Restarts of 400 at most: with 154 coefficients they are expected at their limit (3 × 154 ≥ 400), with
    66 after 198 iterations; no polish round expected. At most: every restart to 400, every polish round (3)."""
    options = _options(starts=16, restarts=4, max_iterations=400, screen_iterations=40, polish_rounds=3)
    wide, narrow = Timing(0.1, 1.0, {}, coefficients=154), Timing(0.1, 1.0, {}, coefficients=66)
    assert sequence_seconds(options, 3, 2, wide) == pytest.approx(3 * (1040 * 0.1 + 10 * 1.0))
    assert sequence_seconds(options, 3, 2, narrow) == pytest.approx(3 * ((320 + 2 * 158) * 0.1 + 10 * 1.0))
    assert sequence_seconds(options, 3, 2, narrow, most=True) == pytest.approx(3 * (2240 * 0.1 + 13 * 1.0))


def test_the_largest_sizes_that_fit_the_budget_are_chosen():
    options = _options(starts=16, restarts=4, max_iterations=400, screen_iterations=40)
    timing = Timing(iteration=0.1, run=0.0, pieces={}, coefficients=154)
    sized, seconds = sizes_within(250.0, options, 3, 2, timing)
    assert (sized["starts"], sized["restarts"], sized["max_iterations"], sized["polish_rounds"]) == (8, 2, 400, 1)
    larger = _options(starts=16, restarts=4, max_iterations=400, screen_iterations=40, polish_rounds=1)
    assert sequence_seconds(larger, 3, 2, timing) > 250.0 >= seconds  # the size before it does not fit
    smallest, over = sizes_within(1.0, options, 3, 2, timing)
    assert "starts" not in smallest and (smallest["restarts"], smallest["max_iterations"]) == SIZES[-1][1:]
    assert over > 1.0  # said: more than the budget


def test_a_problem_s_times_are_measured_on_real_solver_iterations():
    problem = load_problem(CONFIGS / "smoke.yaml")
    excitation = build_excitation(problem)
    alpha = excitation.random_start(np.random.default_rng(0))
    timing = measure(excitation, problem.optimizer, alpha)
    assert timing.iteration > 0 and timing.run >= 0 and timing.coefficients == alpha.size
    assert set(timing.pieces) == {"criterion"} | {c.name for c in excitation.constraints}
    assert all(t > 0 for t in timing.pieces.values())
