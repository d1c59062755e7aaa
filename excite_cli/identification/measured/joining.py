"""A run recorded in several files (positions, velocities and efforts logged apart) joined into one
table: rows paired by time stamp after each file is sorted by its stamps, a stamp given twice
refused, and a run cut to the span every file covers only with a warning naming the seconds lost."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from excite_cli.errors import ExciteError, ExciteWarning
from excite_cli.identification.measured.files import Table

#: Fewest rows a file of a several-file run may have: fewer are no recording (a header and a stray line).
FEWEST_ROWS = 10


def _in_time_order(path: Path, table: Table, time: int | str, drop: bool) -> tuple[np.ndarray, Table]:
    """The stamps of ``table`` (T,) [s] and the table, its rows sorted by them; with ``drop``, rows whose
    stamp is not a number left out and counted in ``Table.dropped``.

    Raises:
        ExciteError: a stamp that is not a number (without ``drop``), or one that two rows share (naming
            the file and their lines).
    """
    stamps = table.column(time, "time", path)
    bad = ~np.isfinite(stamps)
    if bad.any() and not drop:
        raise ExciteError(
            "data",
            f"{path.name}: NaN or missing time stamp at line {table.lines[np.flatnonzero(bad)[0]]} "
            "(data.bad_rows: drop leaves such rows out)",
        )
    if bad.any():
        table = Table(table.names, table.values[~bad], table.dropped + int(bad.sum()), table.lines[~bad], table.unread)
        stamps = stamps[~bad]
    order = np.argsort(stamps, kind="stable")
    stamps = stamps[order]
    repeated = np.flatnonzero(np.diff(stamps) == 0)
    if repeated.size:
        k = repeated[0]
        raise ExciteError(
            "data.runs.file",
            f"{path.name} has two rows at time {stamps[k]:g} s (lines {table.lines[order[k]]} and "
            f"{table.lines[order[k + 1]]}); expected one row per time stamp",
        )
    return stamps, Table(table.names, table.values[order], table.dropped, table.lines[order], table.unread)


def join_tables(
    tables: list[tuple[Path, Table]], time: int | str | None, rate: float | None = None, drop: bool = False
) -> Table:
    """One table of the files of one run (positions, velocities and efforts recorded apart): the rows
    whose ``time`` column holds the same stamp in every file, in time order (each file's rows sorted
    by their stamps first), or, without a time column, the rows of the same index, up to the
    shortest file. A file whose rows reach beyond the others' is cut, with a warning naming it and
    the seconds lost (``rate`` [Hz]: the sample rate of files without a time column); a row whose stamp
    is not a number is refused, or with ``drop`` (``data.bad_rows: drop``) left out and counted. The columns are
    named ``<file stem>/<column>`` (e.g. ``effort/panda_joint1``), after a first column ``time`` of
    the common stamps; by position they count from 0 over the files in order, after that column.

    Raises:
        ExciteError: a file with fewer than ``FEWEST_ROWS`` rows (naming it), a file with two
            rows at one stamp or (without ``drop``) a stamp that is not a number; files that share fewer
            than half of their time stamps.
    """
    sizes = {path: t.values.shape[0] for path, t in tables}
    longest, shortest = max(sizes, key=sizes.get), min(sizes, key=sizes.get)
    if sizes[shortest] < FEWEST_ROWS:
        raise ExciteError(
            "data.runs.file",
            f"{shortest.name} has {sizes[shortest]} row(s) where {longest.name} has {sizes[longest]}; expected "
            f"at least {FEWEST_ROWS} in every file of one recording (a run of several files pairs their rows)",
            shortest,
        )
    if time is None:
        count = min(t.values.shape[0] for _, t in tables)
        rows = [np.arange(count) for _ in tables]
        stamps = np.arange(count, dtype=float)
        lost = {path: (t.values.shape[0] - count) / (rate or 1.0) for path, t in tables}
    else:
        ordered = [(path, *_in_time_order(path, t, time, drop)) for path, t in tables]
        tables = [(path, t) for path, _, t in ordered]
        stamps = ordered[0][1]
        for _, other, _ in ordered[1:]:
            stamps = np.intersect1d(stamps, other)
        if stamps.size < 0.5 * min(s.size for _, s, _ in ordered):
            raise ExciteError(
                "data.runs.file",
                f"{', '.join(p.name for p, _ in tables)} share {stamps.size} of their time stamps; expected files of "
                "one recording with the same time column",
            )
        rows = [np.searchsorted(s, stamps) for _, s, _ in ordered]
        lost = {path: (s[-1] - s[0]) - (stamps[-1] - stamps[0]) for path, s, _ in ordered}
    cut = {path: seconds for path, seconds in lost.items() if seconds > 0}
    if cut:
        warnings.warn(
            f"the run of {' + '.join(p.name for p, _ in tables)} is cut to the span every file covers: "
            + ", ".join(f"{p.name} loses {seconds:.3g} s" for p, seconds in cut.items())
            + ("" if time is not None else " (files without a time column are paired row by row)"),
            ExciteWarning,
        )
    return Table(
        ["time"] + [f"{path.stem}/{name}" for path, t in tables for name in t.names],
        np.column_stack([stamps] + [t.values[r] for (_, t), r in zip(tables, rows)]),
        sum(t.dropped for _, t in tables),
        tables[0][1].lines[rows[0]],
    )
