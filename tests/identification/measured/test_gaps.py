"""Gaps in a recording are cut at, never interpolated across: found by time and length, said in a
warning, and a run with a 2 s gap identifies the friction it holds as the whole run does."""

import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import CONFIGS

from excite_cli.config_file import load_problem
from excite_cli.errors import ExciteError, ExciteWarning
from excite_cli.identification.config import IdentifyProblem, PreprocessingConfig
from excite_cli.identification.measured.gaps import MIN_PIECE_S, find_gaps, missing_messages, split_at_gaps
from excite_cli.identification.measured.measurements import Run
from excite_cli.identification.measured.preprocessing import choose_cutoff, preprocess
from excite_cli.identification.pipeline import run_identification

DATA = Path(__file__).resolve().parents[3] / "data" / "panda_simulated"


def _run(time: np.ndarray) -> Run:
    q = np.sin(time)[:, None]
    return Run("rec.csv", "fit", time, q, None, None, 2 * q, dropped=3)


def test_jitter_and_dropped_messages_are_no_gaps_but_a_stall_is():
    """500 Hz with ±20 % jitter and 1 % of the messages dropped: no gap; a 0.5 s stall: one, where it is."""
    rng = np.random.default_rng(0)
    time = np.arange(5000) / 500.0 + rng.uniform(-0.0004, 0.0004, 5000)
    time = time[rng.random(5000) > 0.01]
    assert find_gaps(time) == []
    stalled = np.concatenate([time[time < 4.0], time[time > 4.5]])
    [gap] = find_gaps(stalled)
    assert gap.start == pytest.approx(4.0, abs=0.003) and gap.length == pytest.approx(0.5, abs=0.005)


def test_single_missing_messages_are_counted_and_are_no_gap():
    """A 40 s, 500 Hz recording with 200 single messages missing (and one missing three in a row)."""
    rng = np.random.default_rng(1)
    time = np.arange(20_000) / 500.0 + rng.uniform(-0.0002, 0.0002, 20_000)
    lost = rng.choice(np.arange(10, 19_990, 50), 200, replace=False)
    time = np.delete(time, lost)
    assert find_gaps(time) == [] and missing_messages(time) == 200
    assert missing_messages(np.delete(time, [5001, 5002, 5003])) == 203


def _rows(time: np.ndarray, q: np.ndarray) -> int:
    """Regressor rows identify keeps of a fit run (every piece between gaps filtered on its own)."""
    cfg = PreprocessingConfig()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExciteWarning)
        pieces = split_at_gaps(Run("rec.csv", "fit", time, q, None, None, q.copy()))
    cutoff, _ = choose_cutoff(pieces, cfg)
    return sum(preprocess(p, cfg, cutoff).filter.kept(p.time.size) for p in pieces)


def test_a_gap_costs_the_gap_and_the_filter_s_edges_not_a_fifth_of_the_rows():
    """A 0.5 s gap in the middle of a 40 s, 500 Hz recording costs 4.4 % of the rows (≤ 5 %): the gap
    and two edges of 3 cut-off periods; the decimation step of each piece is the whole run's (500 Hz
    to 200 Hz rounded 2 or 3 by the last digits of each piece's rate: 20 % more or fewer rows)."""
    time = np.arange(20_000) / 500.0
    rng = np.random.default_rng(0)
    q = np.column_stack([np.sin(2 * np.pi * 0.1 * k * time + rng.uniform(0, 6)) / k for k in range(1, 6)])
    keep = ~((time > 20.0) & (time < 20.5))
    whole, gapped = _rows(time, q), _rows(time[keep], q[keep])
    assert 0.03 < 1.0 - gapped / whole <= 0.05


def test_a_run_is_cut_at_its_gaps_and_a_piece_too_short_to_filter_is_left_out_and_said():
    time = np.concatenate([np.arange(0, 3, 0.01), np.arange(5, 5 + 0.5 * MIN_PIECE_S, 0.01), np.arange(7, 10, 0.01)])
    with pytest.warns(ExciteWarning) as said:
        pieces = split_at_gaps(_run(time))
    assert [p.name for p in pieces] == ["rec.csv [0.000–2.990 s]", "rec.csv [7.000–9.990 s]"]
    assert [p.dropped for p in pieces] == [3, 0]  # counted once
    np.testing.assert_array_equal(pieces[1].tau, 2 * np.sin(pieces[1].time)[:, None])
    [message] = [str(w.message) for w in said]
    assert "2 gap(s) in the recording (2.010 s at 2.990 s; 1.010 s at 5.990 s)" in message
    assert "left out, too short to filter (under 2 s): 5.000–5.990 s" in message
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        whole = _run(np.arange(0, 3, 0.01))
        [same] = split_at_gaps(whole)
        assert same is whole  # no gap: as it is, unsaid
        assert len(split_at_gaps(_run(time), quiet=True)) == 2  # read again: not said twice


def test_a_recording_whose_every_piece_is_too_short_is_refused_by_its_gaps_on_its_own_clock():
    """Pieces of 1.5 s between 0.5 s gaps, on a bag's clock (epoch seconds): refused, never
    interpolated across, each gap placed from the recording's start."""
    time = 1_795_600_000.0 + np.concatenate(
        [np.arange(0, 1.5, 0.005), np.arange(2, 3.5, 0.005), np.arange(4, 5.5, 0.005)]
    )
    with pytest.raises(
        ExciteError,
        match=r"rec.csv: 2 gap\(s\) in the recording \(0.505 s at 1.495 s; 0.505 s at 3.495 s\) leave no piece",
    ):
        split_at_gaps(_run(time))


@pytest.mark.end_to_end
def test_a_2_s_gap_identifies_the_friction_as_the_whole_recording_does(tmp_path, simulated_identification):
    """The shipped simulated runs (Coulomb 0.6 Nm and viscous 0.4 Nm·s/rad undeclared on every joint)
    with 2 s cut out of the middle of the fit run: the same effects, every value within 10 % of the
    whole run's, and the gap named; the two pieces stay one run (an offset per piece absorbed joint
    5's Coulomb friction, ±0.6 Nm, and the validation error went from 0.6 % to 4.3 %). Interpolated
    across, the gap gave the wrong friction model."""
    folder = tmp_path / "data" / "panda_simulated"
    shutil.copytree(DATA, folder)
    lines = (folder / "run_1.csv").read_text().splitlines()
    time = np.array([float(line.split(",", 1)[0]) for line in lines[1:]])
    middle = 0.5 * (time[0] + time[-1])
    keep = [lines[0]] + [line for line, t in zip(lines[1:], time) if not middle - 1.0 < t < middle + 1.0]
    (folder / "run_1.csv").write_text("\n".join(keep) + "\n")
    config = yaml.safe_load((CONFIGS / "panda_identify_simulated.yaml").read_text())
    (tmp_path / "configs").mkdir()
    (tmp_path / "configs" / "gap.yaml").write_text(yaml.safe_dump(config))
    problem = load_problem(tmp_path / "configs" / "gap.yaml", IdentifyProblem)
    with pytest.warns(ExciteWarning, match=r"run_1\.csv: 1 gap\(s\) in the recording \(2\.00\d s at"):
        report = run_identification(problem)[0]
    assert report.run_names == [r.label for r in problem.data.runs]  # the pieces are one run (one offset each)
    whole = simulated_identification[1]
    found, reference = ({(e, j): v for e, j, v, _ in r.effect_values()} for r in (report, whole))
    assert found.keys() == reference.keys() and len(found) == 14
    for key, value in reference.items():
        assert found[key] == pytest.approx(value, rel=0.10), key


def test_check_shows_a_run_s_gaps(tmp_path):
    """``check`` on an identify config names each run's gaps (where identify cuts it), not only the
    rows dropped."""
    from excite_cli.workflows.check_identify import plan_identify

    folder = tmp_path / "data" / "panda_simulated"
    shutil.copytree(DATA, folder)
    lines = (folder / "run_2.csv").read_text().splitlines()
    keep = [lines[0]] + [line for line in lines[1:] if not 3.0 < float(line.split(",", 1)[0]) < 3.5]
    (folder / "run_2.csv").write_text("\n".join(keep) + "\n")
    (tmp_path / "configs").mkdir()
    shutil.copy(CONFIGS / "panda_identify_simulated.yaml", tmp_path / "configs" / "gap.yaml")
    runs = plan_identify(load_problem(tmp_path / "configs" / "gap.yaml", IdentifyProblem)).runs
    assert runs[0].gaps == ()
    [gap] = runs[1].gaps
    assert gap.start == pytest.approx(3.0) and gap.length == pytest.approx(0.5, abs=1e-6)
