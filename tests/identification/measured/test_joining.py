"""A run recorded in several files: rows paired by their time stamps whatever each file's row order,
a stamp given twice refused, a run cut to the common span only with a warning naming the seconds."""

from pathlib import Path

import numpy as np
import pytest

from excite_cli.errors import ExciteError, ExciteWarning
from excite_cli.identification.measured.files import Table
from excite_cli.identification.measured.joining import join_tables


def _table(time: np.ndarray, values: np.ndarray, name: str) -> Table:
    return Table(["time", name], np.column_stack([time, values]), 0, np.arange(time.size) + 2)


TIME = np.arange(100) / 100.0


def test_rows_are_paired_by_stamp_whatever_each_file_s_order():
    rng = np.random.default_rng(0)
    order = rng.permutation(TIME.size)
    q, tau = np.sin(TIME), np.cos(TIME)
    joined = join_tables(
        [(Path("q.csv"), _table(TIME, q, "q")), (Path("tau.csv"), _table(TIME[order], tau[order], "tau"))], "time"
    )
    assert joined.names == ["time", "q/time", "q/q", "tau/time", "tau/tau"]
    np.testing.assert_array_equal(joined.values[:, 0], TIME)
    np.testing.assert_array_equal(joined.values[:, 4], tau)  # each torque beside its own instant


def test_a_stamp_given_twice_names_the_file_and_its_lines():
    stamps = TIME.copy()
    stamps[7] = stamps[6]
    tables = [(Path("q.csv"), _table(TIME, TIME, "q")), (Path("tau.csv"), _table(stamps, TIME, "tau"))]
    with pytest.raises(ExciteError, match=r"tau.csv has two rows at time 0.06 s \(lines 8 and 9\)"):
        join_tables(tables, "time")


def test_a_file_covering_part_of_the_run_cuts_it_with_the_seconds_lost():
    tables = [(Path("q.csv"), _table(TIME, TIME, "q")), (Path("tau.csv"), _table(TIME[:70], TIME[:70], "tau"))]
    with pytest.warns(ExciteWarning, match="q.csv loses 0.3 s"):
        joined = join_tables(tables, "time")
    assert joined.values.shape[0] == 70


def test_files_without_time_are_paired_row_by_row_and_the_cut_is_said_in_seconds():
    tables = [(Path("q.csv"), _table(TIME, TIME, "q")), (Path("tau.csv"), _table(TIME[:50], TIME[:50], "tau"))]
    with pytest.warns(ExciteWarning, match=r"q.csv loses 0.5 s \(files without a time column are paired row by row\)"):
        joined = join_tables(tables, None, rate=100.0)
    np.testing.assert_array_equal(joined.values[:, 2], joined.values[:, 4])


def test_files_of_one_recording_join_without_a_warning(recwarn):
    join_tables([(Path("q.csv"), _table(TIME, TIME, "q")), (Path("tau.csv"), _table(TIME, TIME, "tau"))], "time")
    assert not [w for w in recwarn if issubclass(w.category, ExciteWarning)]


def test_a_stamp_that_is_no_number_is_refused_or_dropped_and_counted():
    """Issue 62: a NaN stamp in one file of a several-file run was left out silently ("dropped 0")."""
    stamps = TIME.copy()
    stamps[40] = np.nan
    tables = [(Path("q.csv"), _table(TIME, TIME, "q")), (Path("tau.csv"), _table(stamps, TIME, "tau"))]
    with pytest.raises(ExciteError, match=r"tau.csv: NaN or missing time stamp at line 42 \(data.bad_rows: drop"):
        join_tables(tables, "time")
    joined = join_tables(tables, "time", drop=True)  # q.csv's row at 0.40 s then has no partner
    assert joined.dropped == 1 and joined.values.shape[0] == TIME.size - 1


def test_a_file_of_one_row_is_the_one_named():
    """Issue 62: a one-row file in a several-file run was blamed on another file (its 2001 rows)."""
    tables = [(Path("q.csv"), _table(TIME, TIME, "q")), (Path("tau.csv"), _table(TIME[:1], TIME[:1], "tau"))]
    with pytest.raises(ExciteError, match=r"tau.csv has 1 row\(s\) where q.csv has 100") as error:
        join_tables(tables, "time")
    assert error.value.value == Path("tau.csv")
