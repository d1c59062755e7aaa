"""The HDF5 helpers every excite file uses (h5py): opening for reading with one clear error, writing
whole or not at all (:mod:`excite_cli.atomic`) with creation time and package versions, string
datasets. The optimize-result schema is in :mod:`excite_cli.storage.results`, the identify report's
in :mod:`excite_cli.identification.reporting.report_file`."""

from __future__ import annotations

import io
from contextlib import contextmanager
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path
from typing import Iterator, Sequence

import h5py
import numpy as np

from excite_cli.atomic import MARK, atomic_bytes
from excite_cli.errors import ExciteError
from excite_cli.inputs import input_file
from excite_cli.kernels import describe

#: Rows written at once by :func:`write_parts` (16 chunks of 4096; a few MB).
WRITE_ROWS = 65536
VERSIONED_PACKAGES = ("excite", "pin", "coal", "numpy", "scipy", "h5py", "example-robot-data")


@contextmanager
def atomic_h5(path: Path, field: str = "output") -> Iterator[h5py.File]:
    """An HDF5 file built in memory, with its creation time (UTC, ISO 8601) and the versions of the
    packages results depend on and the kernels it computed with (:func:`~excite_cli.kernels.describe`)
    as root attributes, then written whole by :func:`atomic_bytes`. HDF5 never writes to the disk
    itself: its write errors (a full disk) end in a crash or in unraisable errors at close, Python's
    in one :class:`CannotWrite`.

    Raises:
        CannotWrite: the file cannot be written.
    """
    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        f.attrs["written_by"] = MARK
        f.attrs["created"] = datetime.now(timezone.utc).isoformat(timespec="seconds")
        for name, version in package_versions().items():
            f.attrs[f"version_{name}"] = version
        f.attrs["kernels"] = describe()
        yield f
    with buffer.getbuffer() as view:  # the file's bytes without a copy of them (it can be most of the memory)
        atomic_bytes(path, view, field)


@contextmanager
def open_h5(path: Path, field: str = "result") -> Iterator[h5py.File]:
    """An HDF5 file opened for reading.

    Args:
        field: the config field or argument that named ``path`` (e.g. ``sequence.prior``), for the messages.

    Raises:
        FileNotFound: no file at ``path``.
        ExciteError: a folder, FIFO or device (:func:`~excite_cli.inputs.input_file`), the file is
            not HDF5, or reading it in the block failed (a missing or empty dataset, a link that
            leads nowhere, a value of the wrong type: a damaged file).
    """
    path = input_file(path, field, "HDF5 file")
    try:
        with h5py.File(path, "r") as f:
            yield f
    except OSError as exc:
        raise ExciteError(field, f"cannot read {path} as HDF5: {_short(exc)}", path, "an HDF5 file") from None
    except (KeyError, RuntimeError, ValueError, TypeError, IndexError) as exc:
        raise ExciteError(field, f"{path} is damaged or not an excite file: {_short(exc)}", path) from None


def _short(exc: Exception) -> str:
    """An error's words on one line, at most 160 characters."""
    return " ".join(str(exc).split())[:160]


def package_versions() -> dict[str, str]:
    """Installed versions of the packages a result depends on ("not installed" for a missing one)."""
    versions = {}
    for name in VERSIONED_PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


def write_strings(group: h5py.Group, name: str, values: Sequence[str]) -> None:
    """A dataset ``name`` of variable-length UTF-8 strings in ``group``."""
    group.create_dataset(name, data=np.array(values, dtype=h5py.string_dtype()))


def write_table(group: h5py.Group, name: str, rows: Sequence[tuple], fields: str, **attrs) -> h5py.Dataset:
    """A compound dataset ``name`` in ``group`` of ``rows`` (tuples), its fields ``"name:type ..."``
    (numpy type codes, ``str`` for a UTF-8 string), and ``attrs`` on it."""
    dtype = [(f, h5py.string_dtype() if t == "str" else t) for f, t in (x.split(":") for x in fields.split())]
    data = group.create_dataset(name, data=np.array(list(rows), dtype=dtype))
    data.attrs.update(attrs)
    return data


def read_strings(group: h5py.Group, name: str) -> list[str]:
    """The strings of a dataset written by :func:`write_strings` (bytes decoded)."""
    return [v.decode() if isinstance(v, bytes) else str(v) for v in group[name][()]]


def write_parts(group: h5py.Group, name: str, parts: list[np.ndarray], columns: int) -> h5py.Dataset:
    """One dataset (M, columns) of the rows of ``parts`` ((M_k, columns) each, in order), compressed
    (gzip with byte shuffling, 4096-row chunks) and written ``WRITE_ROWS`` rows at a time: no stacked
    copy, and ``parts`` is emptied as they are written, so that a part's memory is freed while the
    file (built in memory by :func:`atomic_h5`) grows by as much."""
    total = sum(part.shape[0] for part in parts)
    # a dataset without rows or without columns (a model with no effect columns) has no chunks to compress
    chunked = total > 0 and columns > 0
    options = {"compression": "gzip", "shuffle": True, "chunks": (min(total, 4096), columns)} if chunked else {}
    data = group.create_dataset(name, shape=(total, columns), dtype="f8", **options)
    at = 0
    while parts:
        part = parts.pop(0)
        for lo in range(0, part.shape[0], WRITE_ROWS):  # h5py copies what it writes: a slice at a time
            rows = part[lo : lo + WRITE_ROWS]
            data[at : at + rows.shape[0]] = rows
            at += rows.shape[0]
    return data
