"""What identify prints of its search: a row per step of the kept search, and every start's outcome."""

from dataclasses import replace
from types import SimpleNamespace

from excite_cli.console.effect_search import search
from excite_cli.identification.choice.admission import FAMILY_FOLDS, Admission


def test_a_row_per_step_and_the_kept_start_named(simulated_identification):
    _, report, *_ = simulated_identification
    steps, starts, rule = search(report)
    sel = report.selection
    assert steps.row_count == len(sel.steps)
    assert f"{sel.searches[sel.chosen].start}: " in starts and starts.count("(kept)") == 1
    assert rule.startswith(f"effects admitted by: {sel.admission}") and f"{sel.folds} folds by {sel.folds_by}" in rule


def test_four_recordings_are_said_to_test_each_move_alone(simulated_identification):
    """The paired test on 4 folds tests each move alone (no family): the report says so; on 5, not."""
    _, report, *_ = simulated_identification
    for folds, said in ((4, True), (FAMILY_FOLDS, False)):
        folds_of = SimpleNamespace(folds=folds, by_recording=True)  # what the line reads of the folds
        selection = replace(report.selection, admission=Admission.PAIRED, cross_validation=folds_of)
        rule = search(replace(report, selection=selection))[-1]
        assert ("each move is tested alone" in rule) is said, rule
