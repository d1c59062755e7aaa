"""Output paths, checked before any computation, so a bad path fails in a second rather than after
a run, and an existing result is never replaced by accident."""

from __future__ import annotations

import os
from pathlib import Path

from excite_cli.errors import ExciteError, OutputExists


def check_target(path: Path, field: str, force: bool = False, exists_ok: bool = False) -> Path:
    """Check that ``path`` can be written, without creating anything.

    Args:
        path: the file to write (its folder is created later, when the result is written).
        field: the argument or config field that named it, for the messages (e.g. ``output``).
        force: replacing an existing file is allowed.
        exists_ok: an existing file is expected (a result to resume).

    Returns:
        ``path``.

    Raises:
        OutputExists: the file exists and neither ``force`` nor ``exists_ok``.
        ExciteError: ``path`` is a folder or not a regular file (a device, a FIFO), a file is in the
            way of its folder, or its nearest existing folder is not writable.
    """
    path = Path(path)
    if path.is_dir():
        raise ExciteError(field, f"{path} is a folder", path, "a file name")
    if path.exists() and not path.is_file():  # a device, FIFO or socket is never replaced, even with --force
        raise ExciteError(field, f"{path} is not a regular file", path, "a file name")
    if path.exists() and not (force or exists_ok):
        raise OutputExists(field, path)
    folder = path.parent
    while not folder.exists():
        folder = folder.parent
    if not folder.is_dir():
        raise ExciteError(field, f"cannot create the folder of {path}: {folder} is a file", path)
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ExciteError(field, f"cannot write into {folder} (permission denied)", path)
    return path


def check_folder(folder: Path, names: list[str], field: str, force: bool = False) -> Path:
    """Check that the files ``names`` can be written into ``folder`` (see :func:`check_target`).

    Raises:
        ExciteError: ``folder`` is a file, or a check of :func:`check_target` fails for a name.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ExciteError(field, f"{folder} is a file, not a folder", folder, "a folder")
    for name in names:
        check_target(folder / name, field, force)
    return folder
