"""What identify prints of its search: a row per step of the kept search, and every start's outcome."""

from excite_cli.console.effect_search import search


def test_a_row_per_step_and_the_kept_start_named(simulated_identification):
    _, report, *_ = simulated_identification
    steps, starts, rule = search(report)
    sel = report.selection
    assert steps.row_count == len(sel.steps)
    assert f"{sel.searches[sel.chosen].start}: " in starts and starts.count("(kept)") == 1
    assert rule.startswith(f"effects admitted by: {sel.admission}") and f"{sel.folds} folds by {sel.folds_by}" in rule
