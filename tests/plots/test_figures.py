"""The figures, checked by the data they draw (not by pixels): the figure each plot function hands
to save_figure is kept and its lines read back against the results and reports they come from."""

import numpy as np
import pytest

import excite_cli.plots.comparison as comparison_plots
import excite_cli.plots.identification as identification_plots
import excite_cli.plots.optimize as optimize_plots
import excite_cli.plots.tracks as tracks_plots
from excite_cli.collision.world import world_shapes
from excite_cli.config import EnvironmentConfig
from excite_cli.plots.figure import save_figure
from excite_cli.plots.shapes import draw_shape, stadium
from excite_cli.storage.results import read_iterations


@pytest.fixture
def kept(monkeypatch):
    """The figures the plot functions save, kept open instead of written."""
    figures = []
    for module in (optimize_plots, tracks_plots, identification_plots, comparison_plots):
        monkeypatch.setattr(module, "save_figure", lambda fig, path, dpi: figures.append(fig) or path)
    return figures


@pytest.fixture(scope="module")
def results(optimized):
    from excite_cli.config_file import result_problem
    from excite_cli.design.resolve import build_excitation

    excitation = build_excitation(result_problem(optimized))
    return excitation, read_iterations(optimized, excitation)


def test_a_figure_is_written_as_a_whole_png_and_closed(tmp_path):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    path = save_figure(fig, tmp_path / "f.png", 50)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and not plt.fignum_exists(fig.number)
    assert not (tmp_path / ".f.png.partial").exists()


def test_table_one_chart_draws_each_iteration_s_condition_numbers(kept, results, tmp_path):
    _, iterations = results
    optimize_plots.plot_condition_numbers(tmp_path / "c.png", iterations)
    own, stacked = kept[0].axes[0].get_lines()[:2]
    np.testing.assert_array_equal(own.get_ydata(), [r.cond_own for r in iterations])
    np.testing.assert_array_equal(stacked.get_ydata(), [r.cond_stacked for r in iterations])
    np.testing.assert_array_equal(stacked.get_xdata(), [1, 2, 3])


def test_the_comparison_draws_random_selection_beside_the_optimized_motions(kept, tmp_path):
    random_table = {"iteration": [1, 2], "cond_own": [600.0, 700.0], "cond_stacked": [600.0, 500.0]}
    optimized = {"iteration": [1, 2], "cond_own": [60.0, 70.0], "cond_stacked": [60.0, 50.0]}
    comparison_plots.plot_comparison(tmp_path / "c.png", random_table, optimized)
    own, stacked = kept[0].axes
    assert [b.get_height() for b in stacked.patches] == [600.0, 500.0, 60.0, 50.0]
    assert [b.get_height() for b in own.patches] == [600.0, 700.0, 60.0, 70.0]


def test_trajectory_plot_draws_q_of_every_joint_and_its_limits(kept, results, tmp_path):
    excitation, iterations = results
    limits = excitation.limits
    optimize_plots.plot_trajectories(
        tmp_path / "t.png", excitation.robot.joint_names, iterations, limits.lower, limits.upper
    )
    first = kept[0].axes[0]  # q of iteration 1
    drawn = [line.get_ydata() for line in first.get_lines() if len(line.get_ydata()) == len(iterations[0].time)]
    for j in range(excitation.robot.n_joints):
        assert any(np.array_equal(y, iterations[0].q[:, j]) for y in drawn)
    levels = {float(y[0]) for line in first.get_lines() if len(set(y := line.get_ydata())) == 1}
    assert {float(x) for x in limits.lower[0]} <= levels and {float(x) for x in limits.upper[0]} <= levels


def test_residual_plot_draws_measured_and_both_predictions(kept, simulated_identification, tmp_path):
    _, report, *_ = simulated_identification
    identification_plots.plot_identification(tmp_path / "r.png", report)
    measured, before, after = (line.get_ydata() for line in kept[0].axes[0].get_lines()[:3])
    n = len(report.joints)
    np.testing.assert_array_equal(measured, report.validation.tau.reshape(-1, n)[:, 0])
    np.testing.assert_array_equal(before, report.predicted_before[:, 0])
    np.testing.assert_array_equal(after, report.predicted_after[:, 0])


def test_a_capsule_outline_keeps_its_radius_from_the_segment():
    a, b, radius = np.array([0.0, 0.0]), np.array([1.0, 0.5]), 0.2
    outline = stadium(a, b, radius)
    d = b - a
    t = np.clip((outline - a) @ d / (d @ d), 0.0, 1.0)
    np.testing.assert_allclose(np.linalg.norm(outline - (a + t[:, None] * d), axis=1), radius, atol=1e-12)


def test_a_floor_is_drawn_as_its_trace_with_the_far_side_filled():
    import matplotlib.pyplot as plt

    (floor,) = world_shapes(
        EnvironmentConfig.model_validate(
            {"shapes": [{"name": "floor", "type": "half_space", "point": [0, 0, -0.5], "normal": [0, 0, 1]}]}
        )
    )
    fig, ax = plt.subplots()
    ax.set_xlim(-1, 1), ax.set_ylim(-1, 1)
    draw_shape(ax, floor, 0, 1.0)
    trace = ax.get_lines()[0].get_ydata()
    filled = ax.patches[0].get_xy()
    plt.close(fig)
    np.testing.assert_allclose(trace, -0.5)
    assert filled[:, 1].min() < -0.5 and filled[:, 1].max() == pytest.approx(-0.5)  # below the floor's plane
