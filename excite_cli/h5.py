"""Files written whole or not at all, and the HDF5 helpers every excite file uses (h5py): opening
for reading with one clear error, atomic writing with creation time and package versions, string
datasets. The optimize-result schema is in :mod:`excite_cli.storage.results`, the identify report's
in :mod:`excite_cli.identification.report_file`."""

from __future__ import annotations

import os
from contextlib import contextmanager
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path
from typing import Iterator, Sequence

import h5py
import numpy as np

from excite_cli.errors import CannotWrite, ExciteError, FileNotFound

VERSIONED_PACKAGES = ("excite", "pin", "coal", "numpy", "scipy", "h5py", "example-robot-data")


@contextmanager
def atomic_path(path: Path, field: str = "output") -> Iterator[Path]:
    """A temporary path ``<path>.partial`` to write to, moved onto ``path`` (``os.replace``, atomic)
    when the block ends without error and removed otherwise, so a crash, Ctrl-C or full disk never
    leaves a half-written ``path``; the folder of ``path`` is created.

    Args:
        field: the config field or argument that named ``path``, for the message.

    Raises:
        CannotWrite: the file cannot be written (``OSError`` in the block or in the move).
    """
    path = Path(path)
    tmp = path.with_name(path.name + ".partial")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        yield tmp
        os.replace(tmp, path)
    except OSError as exc:
        raise CannotWrite(field, path, exc.strerror or exc) from None
    finally:
        tmp.unlink(missing_ok=True)


@contextmanager
def atomic_h5(path: Path, field: str = "output") -> Iterator[h5py.File]:
    """An HDF5 file written through :func:`atomic_path`, with its creation time (UTC, ISO 8601) and
    the versions of the packages results depend on as root attributes.

    Raises:
        CannotWrite: the file cannot be written.
    """
    with atomic_path(path, field) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["created"] = datetime.now(timezone.utc).isoformat(timespec="seconds")
            for name, version in package_versions().items():
                f.attrs[f"version_{name}"] = version
            yield f


@contextmanager
def open_h5(path: Path, field: str = "result") -> Iterator[h5py.File]:
    """An HDF5 file opened for reading.

    Args:
        field: the config field or argument that named ``path`` (e.g. ``sequence.prior``), for the messages.

    Raises:
        FileNotFound: no file at ``path``.
        ExciteError: the file is not HDF5.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFound(field, path)
    try:
        with h5py.File(path, "r") as f:
            yield f
    except OSError as exc:
        raise ExciteError(field, f"cannot read {path} as HDF5: {exc}", path, "an HDF5 file") from None


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
