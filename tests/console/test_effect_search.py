"""What identify prints of its search: a row per step of the kept search, and every start's outcome."""

from dataclasses import replace
from types import SimpleNamespace

from excite_cli.console.effect_search import search
from excite_cli.identification.choice.admission import FAMILY_FOLDS, Admission
from excite_cli.identification.choice.search_record import Step


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


def test_a_removal_of_an_estimate_not_clear_of_zero_says_so_in_its_row(simulated_identification):
    """The search's last removals (an estimate under 3 standard deviations from zero) print the
    estimate's distance instead of a paired test, and their row tried no other move."""
    _, report, *_ = simulated_identification
    sel = report.selection
    kept = sel.searches[sel.chosen]
    term = kept.terms[-1]
    removal = Step("remove", term, kept.terms[:-1], kept.cv_error, kept.cv_error, [], clear_of_zero=1.73)
    searches = list(sel.searches)
    searches[sel.chosen] = replace(kept, steps=[*kept.steps, removal])
    paired = replace(sel, searches=searches, admission=Admission.PAIRED, at_start=False)
    table = search(replace(report, selection=paired))[0]
    last = [column._cells[-1] for column in table.columns]
    assert last[1] == f"− {term.label(report.joints)} (estimate 1.7 std from 0)"
    assert last[3] == "—" and last[4] == "—"
