"""Output paths, checked before any computation, so a bad path fails in a second rather than after
a run, and an existing result is never replaced by accident; a lock beside an output, so two runs
never write it at once."""

from __future__ import annotations

import fcntl
import os
import tempfile
import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from excite_cli.atomic import new_folders, partial_path, remove_stale
from excite_cli.errors import CannotWrite, ExciteError, ExciteWarning, OutputExists


def check_target(path: Path, field: str, force: bool = False, exists_ok: bool = False) -> Path:
    """Check that ``path`` can be written, leaving nothing behind.

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
    try:  # what access() cannot tell (root in /proc, a read-only mount): a nameless file, gone when closed
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise ExciteError(field, f"cannot create a file in {folder} ({exc.strerror})", path) from None
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


@contextmanager
def output_lock(path: Path, field: str) -> Iterator[None]:
    """Hold ``.<name>.lock`` beside ``path`` (an exclusive ``flock``, with this process's id inside) while the block
    runs, so a second run writing ``path`` stops at once instead of replacing the first one's result.
    The lock file is removed when the block ends; one left by a killed run is taken over (the system
    releases its lock), and so is its ``.<name>.partial``, each with a warning
    (:class:`~excite_cli.errors.ExciteWarning`). Folders made for it and left empty are removed
    (:func:`new_folders`).

    Raises:
        ExciteError: another process holds the lock (its id in the message).
        CannotWrite: the lock file cannot be created.
    """
    path = Path(path)
    lock = path.with_name(f".{path.name}.lock")  # hidden, like the .partial files
    with new_folders([lock], field):
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise CannotWrite(field, lock, exc.strerror or exc) from None
        held = False
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                held = os.fstat(fd).st_ino == os.stat(lock).st_ino  # not a lock file its holder just removed
            except OSError:
                pass
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip()  # the running or the killed run's id
            if not held:
                raise ExciteError(
                    field,
                    f"{path} is being written by another excite run (process {holder or '?'})",
                    path,
                    "another output path, or that run to end",
                )
            if holder:
                warnings.warn(f"took over {lock}, left by process {holder}, which was killed", ExciteWarning)
                remove_stale(partial_path(path))
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
            yield
        finally:
            if held:
                lock.unlink(missing_ok=True)
            os.close(fd)
