"""What check prints of a problem's time: the expected and the largest estimate, what one evaluation is made
of and what to cut, from the timing it was given (the solver iterations counted by the restarts' rules)."""

from conftest import CONFIGS

from excite_cli.config_file import load_problem
from excite_cli.console.plans import plan
from excite_cli.search.run_time import Timing
from excite_cli.workflows.check import plan_optimize


def test_the_estimate_is_the_busiest_worker_s_iterations_times_the_timed_ones():
    """The smoke problem: 1 restart of 80 iterations (7 joints, 3 harmonics: 49 coefficients, expected at
    its limit, 3 × 49 ≥ 80), 3 polish rounds, 2 sequential iterations; at 50 ms an iteration and 1 s a run,
    expected 2 × (80 × 0.05 + 1 × 1) = 10 s; with every polish round 2 × (320 × 0.05 + 4 × 1) = 40 s."""
    problem = load_problem(CONFIGS / "smoke.yaml")
    problem.optimizer.workers = 1
    pieces = {"criterion": 0.002, "joint_limits": 0.006}
    timing = Timing(0.05, 1.0, pieces, coefficients=49)
    lines = [line for line in plan(plan_optimize(problem, timing)) if isinstance(line, str)]
    estimate = next(line for line in lines if line.startswith("estimated time"))
    assert estimate.startswith("estimated time: about 10 s, at most 40 s (50 ms per solver iteration")
    assert "80 solver iterations and 1 runs per sequential iteration on the busiest of 1 worker(s)" in estimate
    assert any(line.endswith("joint_limits 75 %, criterion 25 %") for line in lines)
    assert any(line.startswith("to cut the time: fewer starts and restarts") for line in lines)
