"""The sequence never loses ground: an iteration whose restarts all end worse than playing an earlier
motion again plays that motion again (or better), and with ``sequence.replay: false`` it does not.
Truth: stacking a regressor on itself doubles CᵀC and leaves cond unchanged, so replaying iteration
1 keeps iteration 1's stacked cond(C) exactly; with two motions stacked, the motion of their mean
α keeps it to second order in their distance."""

import copy

import numpy as np
import pytest
from conftest import UR5, write_config

from excite_cli.config_file import load_problem
from excite_cli.design.information import PriorInformation
from excite_cli.design.resolve import build_excitation
from excite_cli.search.earlier_optimum import from_earlier_optimum
from excite_cli.search.engine import Engine
from excite_cli.search.kkt import End
from excite_cli.search.optimizer import RestartResult
from excite_cli.search.restarts import RestartContext
from excite_cli.search.sequence import run_sequence


def _small_ur5(tmp_path, replay: bool):
    data = copy.deepcopy(UR5)
    data["trajectory"].update(harmonics=3, cost_samples=20, cost_period=0.4, constraint_period=0.05)
    data["optimizer"] = {"objective": "log_cond", "max_iterations": 400, "restarts": 1, "seed": 1, "workers": 1}
    data["sequence"] = {"iterations": 2, "replay": replay}
    return build_excitation(load_problem(write_config(tmp_path, data)))


def _first_then_short(tmp_path, replay: bool):
    """Iteration 1 optimized to convergence, then iteration 2 whose only restart stops after one
    solver iteration (so it ends near its random start, far worse than iteration 1's motion)."""
    excitation = _small_ur5(tmp_path, replay)
    first = run_sequence(excitation, 1, seed=1)
    excitation.spec.optimizer.max_iterations = 1
    excitation.spec.optimizer.polish_rounds = 0
    return first[0], run_sequence(excitation, 2, seed=1, finished=first)[1]


@pytest.mark.parametrize("replay", [True, False])
def test_an_iteration_never_ends_worse_than_playing_an_earlier_motion_again(tmp_path, replay):
    first, second = _first_then_short(tmp_path, replay)
    again = np.linalg.cond(np.vstack([first.regressor, first.regressor]))
    assert again == pytest.approx(first.cond_stacked, rel=1e-9)  # the truth the guard rests on
    if replay:
        kept = second.best
        assert kept.index == 1 and kept.succeeded and kept.end in (End.EARLIER, End.PROJECTED, End.INSIDE)
        assert second.cond_stacked <= first.cond_stacked * (1 + 1e-9)
        assert second.max_correlation > 0.9 and second.max_violation <= 0.0
    else:
        assert [r.index for r in second.restarts] == [0]
        assert second.cond_stacked > 1.2 * first.cond_stacked  # what the guard prevents


@pytest.mark.parametrize("replay, margin", [(True, 0.0), (False, -1.0)])
def test_no_restart_more_where_the_kept_one_is_as_good_or_replay_is_off(tmp_path, replay, margin):
    """The kept end is as low as the earlier motion (or replay is off, where the earlier motion is
    lower): nothing more runs (the context has no engine: a run would fail)."""
    excitation = _small_ur5(tmp_path, replay)
    earlier = excitation.random_start(np.random.default_rng(0))
    prior = excitation.criterion().regressor(excitation.random_start(np.random.default_rng(1)))
    value = excitation.criterion(prior).value(earlier)
    kept = RestartResult(0, earlier, value - margin, 10, "", 1.0, stop="converged", end=End.PROJECTED)
    context = RestartContext(excitation, None, 2, 1, prior, float("inf"))
    assert from_earlier_optimum(context, [kept], kept, [earlier]) == [kept]


def _log_cond(*rows: np.ndarray) -> float:
    return float(np.log(np.linalg.cond(np.vstack(rows))))


def test_the_mean_motion_keeps_cond_to_second_order_where_replaying_one_keeps_it_to_first(tmp_path):
    """Two motions ε apart stacked: playing one again moves log cond by O(ε), playing the motion of
    their mean α moves it by O(ε²) (CᵀC is smooth in α and stacking a multiple of C₀ᵀC₀ keeps cond):
    halving ε halves the first and quarters the second."""
    excitation = _small_ur5(tmp_path, True)
    regressor = excitation.criterion().regressor
    alpha = excitation.random_start(np.random.default_rng(3))
    direction = excitation.random_start(np.random.default_rng(4)) - alpha
    moved = {}
    for eps in (2e-3, 1e-3):
        C1, C2 = regressor(alpha), regressor(alpha + eps * direction)
        before = _log_cond(C1, C2)
        moved[eps] = (
            abs(_log_cond(C1, C2, C1) - before),
            abs(_log_cond(C1, C2, regressor(alpha + 0.5 * eps * direction)) - before),
        )
    replay, mean = moved[2e-3][0] / moved[1e-3][0], moved[2e-3][1] / moved[1e-3][1]
    assert replay == pytest.approx(2.0, rel=0.1) and mean == pytest.approx(4.0, rel=0.1)
    assert moved[1e-3][1] < 0.05 * moved[1e-3][0]


def test_with_two_earlier_motions_the_guard_starts_from_the_better_one_and_from_their_mean(tmp_path):
    excitation = _small_ur5(tmp_path, True)
    excitation.spec.optimizer.max_iterations = 2
    excitation.spec.optimizer.polish_rounds = 0
    earlier = [excitation.random_start(np.random.default_rng(seed)) for seed in (5, 6)]
    prior = np.vstack([excitation.criterion().regressor(alpha) for alpha in earlier])
    criterion = excitation.criterion(prior)
    kept = RestartResult(0, earlier[0], 1e9, 10, "", 1.0, stop="converged", end=End.PROJECTED)
    with Engine(excitation) as engine:
        context = RestartContext(excitation, engine, 3, 1, PriorInformation.of(prior), float("inf"))
        runs = from_earlier_optimum(context, [kept], kept, earlier)
    lower = min(criterion.value(alpha) for alpha in earlier)
    assert [r.index for r in runs] == [0, 1, 2]
    assert runs[1].start_objective == pytest.approx(lower, rel=1e-9)
    assert runs[2].start_objective == pytest.approx(criterion.value(np.mean(earlier, axis=0)), rel=1e-9)
