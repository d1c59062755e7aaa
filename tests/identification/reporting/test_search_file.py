"""The effects and the search of an identify report as its file holds them: a row per coefficient in
the fit's order, the spread between trajectories NaN when the fit data hold one (the time blocks'
instead), a row per step."""

import h5py
import numpy as np

from excite_cli.identification.reporting.search_file import write_effects, write_search


def test_the_effects_and_steps_are_the_reports(simulated_identification, tmp_path):
    _, report, *_ = simulated_identification
    with h5py.File(tmp_path / "r.h5", "w") as f:
        g = f.create_group("identification")
        write_effects(g, report)
        write_search(g, report)
    with h5py.File(tmp_path / "r.h5") as f:
        effects, steps = f["identification/effects"][()], f["identification/steps"][()]
        clear = f["identification/steps"].attrs["clear_of_zero_std"]
    values = report.effect_values()
    np.testing.assert_array_equal(effects["value"], [v for _, _, v, _ in values])
    fit, b = report.selection.fit, len(report.base_names)
    assert np.all(np.isnan(effects["std_between_trajectories"]))  # one fit run: one trajectory
    assert fit.spread_by == "time blocks" and fit.groups == 6  # identification.folds
    np.testing.assert_array_equal(effects["std_between_time_blocks"], fit.between[b:])
    assert len(steps) == len(report.selection.steps)
    np.testing.assert_array_equal(clear, [s.clear_of_zero for s in report.selection.steps])  # NaN: no such removal
