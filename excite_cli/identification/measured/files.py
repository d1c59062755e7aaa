"""Measured-data files as labs have them, read into one table of numeric columns.

- CSV, TSV, text: columns by header name, or by position (0-based) with or without a header; the
  delimiter (``,`` ``;`` tab or blanks) is detected, a header is a first row that is not all numbers.
- NPZ (numpy), MAT (MATLAB, scipy.io): each 1-D array by its name; a 2-D array ``x`` of T rows as
  ``x[0]``, ``x[1]``, ... (a short-and-wide array is transposed).
- HDF5: datasets as for NPZ; non-numeric datasets are left out.

Rows that cannot be read (a wrong number of values, text where a number belongs) are errors naming
the file and the line, or, with ``bad_rows: drop``, left out and counted.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np
import scipy.io

from excite_cli.errors import ExciteError
from excite_cli.inputs import input_file

DELIMITERS = (",", ";", "\t")
#: Largest CSV or text file read [bytes] (binary formats are read without this bound).
MAX_TEXT_BYTES = 1_000_000_000
#: A number written with a decimal comma (semicolon-separated files of European locales).
DECIMAL_COMMA = re.compile(r"\d,\d")


@dataclass(frozen=True)
class Table:
    """Numeric columns of one file.

    Attributes:
        names: (m,) column names (positions as text for a headerless CSV).
        values: (T, m) values, NaN where a value is missing.
        dropped: rows left out because they could not be read (with ``bad_rows: drop``).
        lines: (T,) line (CSV, 1-based) or row (others, 1-based) of each kept row, for messages.
        unread: names in the file that were not read, with why (an HDF5 link not followed).
    """

    names: list[str]
    values: np.ndarray
    dropped: int
    lines: np.ndarray
    unread: dict[str, str] = field(default_factory=dict)

    def column(self, key: int | str, field: str, path: Path) -> np.ndarray:
        """(T,) the column named ``key`` or at position ``key`` (0-based).

        Raises:
            ExciteError: no such column (the message lists some that exist).
        """
        if isinstance(key, int):
            if key < self.values.shape[1]:
                return self.values[:, key]
            raise ExciteError(
                f"data.columns.{field}", f"{path.name} has {self.values.shape[1]} columns, no column {key} (0-based)"
            )
        if key in self.names:
            return self.values[:, self.names.index(key)]
        if key in self.unread:
            raise ExciteError(f"data.columns.{field}", f"{path.name}: '{key}' is {self.unread[key]}")
        raise ExciteError(
            f"data.columns.{field}",
            f"{path.name} has no column '{key}' (it has: {', '.join(self.names[:12])}"
            f"{', ...' if len(self.names) > 12 else ''})",
        )


def _number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def _split(line: str, delimiter: str | None) -> list[str]:
    return [part.strip() for part in (line.split(delimiter) if delimiter else line.split())]


def _read_text(path: Path, drop: bool) -> Table:
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()  # a byte-order mark is not data
    except UnicodeDecodeError:
        raise ExciteError(
            "data",
            f"{path.name} is not a text file (CSV expected from its name; NPZ, MAT and HDF5 "
            f"files need the .npz, .mat or .h5 ending)",
        ) from None
    numbered = [(k + 1, line) for k, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
    if not numbered:
        raise ExciteError("data", f"{path.name} has no data rows")
    first = numbered[0][1]
    delimiter = max(DELIMITERS, key=first.count) if any(d in first for d in DELIMITERS) else None
    if delimiter == ";" and any(DECIMAL_COMMA.search(line) for _, line in numbered[1:3]):
        numbered = [(k, line.replace(",", ".")) for k, line in numbered]  # 1,5;2,25: decimal commas
    head = _split(first, delimiter)
    header = not all(_number(x) or x == "" for x in head)
    names = head if header else [str(k) for k in range(len(head))]
    body = numbered[1:] if header else numbered
    if not body:
        raise ExciteError("data", f"{path.name} has a header but no data rows")
    try:  # the fast path: every row complete and numeric
        values = np.loadtxt([line for _, line in body], delimiter=delimiter, ndmin=2, dtype=float)
        if values.shape[1] == len(names) and values.shape[0] == len(body):
            return Table(names, values, 0, np.array([number for number, _ in body]))
    except ValueError:
        pass
    rows, kept, dropped = [], [], 0
    for number, line in body:
        parts = _split(line, delimiter)
        try:
            if len(parts) != len(names):
                raise ValueError(
                    f"{len(parts)} values where the {'header has' if header else 'first row has'} {len(names)}"
                )
            rows.append([float(x) if x else np.nan for x in parts])
            kept.append(number)
        except ValueError as exc:
            if not drop:
                reason = str(exc) if "values where" in str(exc) else "a value that is not a number"
                raise ExciteError(
                    "data", f"{path.name}: line {number}: {reason} (data.bad_rows: drop leaves such rows out)"
                ) from None
            dropped += 1
    if not rows:
        raise ExciteError("data", f"{path.name} has a header but no data rows")
    return Table(names, np.array(rows, dtype=float), dropped, np.array(kept))


def _columns(arrays: dict[str, np.ndarray], path: Path, unread: dict[str, str] | None = None) -> Table:
    """1-D arrays by name, 2-D arrays as ``name[k]``, rows along the longer axis (``unread``: see
    :class:`Table`)."""
    names, columns = [], []
    for name, array in arrays.items():
        array = np.asarray(array)
        if array.dtype.kind not in "fiub" or array.ndim == 0 or array.ndim > 2:
            continue
        array = np.squeeze(array) if array.ndim == 2 and 1 in array.shape else array
        if array.ndim == 1:
            names.append(name)
            columns.append(array.astype(float))
        else:
            array = array if array.shape[0] >= array.shape[1] else array.T
            names += [f"{name}[{k}]" for k in range(array.shape[1])]
            columns += [array[:, k].astype(float) for k in range(array.shape[1])]
    lengths = {c.size for c in columns}
    if not columns:
        raise ExciteError("data", f"{path.name} holds no numeric 1-D or 2-D arrays")
    if max(lengths) == 0:
        raise ExciteError("data", f"{path.name} has no data rows (its arrays are empty)")
    if len(lengths) > 1:
        longest = max(lengths)
        keep = [k for k, c in enumerate(columns) if c.size == longest]
        names, columns = [names[k] for k in keep], [columns[k] for k in keep]
    values = np.column_stack(columns)
    return Table(names, values, 0, np.arange(1, values.shape[0] + 1), unread or {})


def _h5_datasets(f: h5py.File) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """The datasets at the root of ``f`` by name, and the names not read with why: links to other
    files are not followed, links that lead nowhere (a missing target, a loop) are left out."""
    arrays, unread = {}, {}
    for name in f:
        link = f.get(name, getlink=True)
        if isinstance(link, h5py.ExternalLink):
            unread[name] = f"a link to {link.filename}:{link.path}, which excite does not follow (copy the data in)"
            continue
        try:
            item = f[name]
        except (KeyError, RuntimeError):
            unread[name] = "a link that leads nowhere (a missing target or a loop)"
            continue
        if isinstance(item, h5py.Dataset):
            arrays[name] = item[()]
    return arrays, unread


def _check_text_size(path: Path) -> None:
    """Refuse a text file too big to read as text, or whose start holds NUL bytes (a binary file or
    a sparse file of zeros under a .csv name)."""
    size = path.stat().st_size
    if size > MAX_TEXT_BYTES:
        raise ExciteError(
            "data",
            f"{path.name} is {size / 1e9:.1f} GB, larger than {MAX_TEXT_BYTES / 1e9:g} GB of text",
            path,
            "a smaller CSV or the data as NPZ, MAT or HDF5",
        )
    with open(path, "rb") as f:
        if b"\0" in f.read(65536):
            raise ExciteError(
                "data",
                f"{path.name} is not a text file (it holds NUL bytes; NPZ, MAT and HDF5 files need the "
                ".npz, .mat or .h5 ending)",
                path,
            )


def read_table(path: Path, drop: bool = False) -> Table:
    """The numeric columns of a measured-data file (module docstring).

    Args:
        path: CSV or text, ``.npz``, ``.mat`` or ``.h5`` / ``.hdf5``.
        drop: leave out rows that cannot be read instead of stopping.

    Raises:
        ExciteError: not a regular file, an unreadable file or row, naming the file (and the line).
    """
    input_file(path, "data.runs", "data file")  # before anything opens it: reading a FIFO waits for a writer
    suffix = path.suffix.lower()
    try:
        if suffix == ".npz":
            with np.load(path, allow_pickle=False) as archive:
                return _columns({name: archive[name] for name in archive.files}, path)
        if suffix == ".mat":
            return _columns({k: v for k, v in scipy.io.loadmat(path).items() if not k.startswith("__")}, path)
        if suffix in (".h5", ".hdf5"):
            with h5py.File(path, "r") as f:
                arrays, unread = _h5_datasets(f)
                return _columns(arrays, path, unread)
    except ExciteError:
        raise
    except Exception as exc:  # a corrupt file makes the parsers raise anything (TypeError, zlib.error, struct.error)
        raise ExciteError(
            "data", f"cannot read {path.name} as {suffix[1:].upper()}: {' '.join(str(exc).split())[:160]}"
        ) from None
    _check_text_size(path)
    return _read_text(path, drop)
