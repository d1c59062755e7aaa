"""Output paths, checked before any computation, so a bad path fails in a second rather than after
a run, and an existing result is never replaced by accident."""

from __future__ import annotations

import os
from pathlib import Path

from excite_cli.errors import ExciteError


def check_target(path: Path, option: str, force: bool = False, exists_ok: bool = False) -> Path:
    """Check that ``path`` can be written, without creating anything.

    Args:
        path: the file to write (its folder is created later, when the result is written).
        option: the option or config field that named it, for the messages (e.g. ``--output``).
        force: replacing an existing file is allowed.
        exists_ok: an existing file is expected (``--resume``).

    Returns:
        ``path``.

    Raises:
        ExciteError: ``path`` is a folder, a file is in the way of its folder, its nearest existing
            folder is not writable, or the file exists and neither ``force`` nor ``exists_ok``.
    """
    path = Path(path)
    if path.is_dir():
        raise ExciteError(f"{option}: {path} is a folder; give a file name")
    if path.exists() and not (force or exists_ok):
        raise ExciteError(f"{option}: {path} exists; use --force to replace it")
    folder = path.parent
    while not folder.exists():
        folder = folder.parent
    if not folder.is_dir():
        raise ExciteError(f"{option}: cannot create the folder of {path}: {folder} is a file")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ExciteError(f"{option}: cannot write into {folder} (permission denied)")
    return path


def check_folder(folder: Path, names: list[str], option: str, force: bool = False) -> Path:
    """Check that the files ``names`` can be written into ``folder`` (see :func:`check_target`).

    Raises:
        ExciteError: ``folder`` is a file, or a check of :func:`check_target` fails for a name.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ExciteError(f"{option}: {folder} is a file, not a folder")
    for name in names:
        check_target(folder / name, option, force)
    return folder
