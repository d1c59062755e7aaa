"""Output paths, checked before any computation, so a bad path fails in a second rather than after
a run, and an existing result is never replaced by accident, nor anything excite did not write, even
with ``force``; a lock beside an output, so two runs never write it at once."""

from __future__ import annotations

import fcntl
import os
import re
import tempfile
import warnings
import zipfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from excite_cli.atomic import MARK_PREFIX, MARK_VERSION, is_mark, new_folders, partial_path, remove_stale
from excite_cli.errors import CannotWrite, ExciteError, ExciteWarning, OutputExists

#: How much of a file's start is read for its mark [bytes].
MARK_WINDOW = 4096
#: A text file excite wrote: a line that begins with the mark and its command, as a ``#`` or ``<!--``
#: comment (``# written by excite 0.1.0 export``), or a JSON schema's ``"$comment"`` (its whole value).
TEXT_MARK = re.compile(
    rf"^[ \t]*(?:(?:# |<!-- ){MARK_PREFIX} {MARK_VERSION} [a-z][a-z-]*(?:[ :,]|-->|$)"
    rf'|"\$comment": "{MARK_PREFIX} schema"$)',
    re.MULTILINE,
)


def written_by_excite(path: Path) -> bool:
    """Whether excite wrote the file at ``path``, by the mark it leaves (:data:`~excite_cli.atomic.MARK`,
    whole: :func:`~excite_cli.atomic.is_mark`): an HDF5 file's ``written_by`` attribute (or the
    ``version_excite`` attribute of earlier versions), a PNG's ``Software`` text chunk, an NPZ's
    ``written_by`` array, or a line of a text file's first or last 4 KiB (:data:`TEXT_MARK`: CSV, YAML,
    JSON, URDF, MJCF, HTML; a recording-like CSV ends with its mark, so that its header is its first row).
    A file that cannot be read is not excite's."""
    try:
        with open(path, "rb") as f:
            head = f.read(MARK_WINDOW)
            f.seek(max(0, os.fstat(f.fileno()).st_size - MARK_WINDOW))
            tail = f.read(MARK_WINDOW)
        if head.startswith(b"\x89HDF"):
            import h5py  # only for an HDF5 file in the way

            with h5py.File(path, "r") as f:
                return is_mark(str(f.attrs.get("written_by", ""))) or "version_excite" in f.attrs
        if head.startswith(b"\x89PNG"):
            return is_mark(_png_software(head))
        if head.startswith(b"PK"):
            import numpy as np  # only for an NPZ in the way

            with np.load(path, allow_pickle=False) as archive:
                return "written_by" in archive.files and is_mark(str(archive["written_by"]))
        return any(TEXT_MARK.search(part.decode("utf-8", errors="replace")) for part in (head, tail))
    except (OSError, ValueError, zipfile.BadZipFile):
        return False


def _png_software(head: bytes) -> str:
    """The ``Software`` text of a PNG's ``tEXt`` chunks among its first bytes ``head``, or ""."""
    at = 8  # after the signature: chunks of length (4 bytes), type (4), data, CRC (4)
    while at + 8 <= len(head):
        length, kind = int.from_bytes(head[at : at + 4], "big"), head[at + 4 : at + 8]
        data = head[at + 8 : at + 8 + length]
        if kind == b"tEXt" and data.startswith(b"Software\x00"):
            return data[len(b"Software\x00") :].decode("latin-1")
        if kind == b"IDAT":
            break
        at += 12 + length
    return ""


def check_target(path: Path, field: str, force: bool = False, exists_ok: bool = False) -> Path:
    """Check that ``path`` can be written, leaving nothing behind.

    Args:
        path: the file to write (its folder is created later, when the result is written).
        field: the argument or config field that named it, for the messages (e.g. ``output``).
        force: replacing an existing file excite wrote (:func:`written_by_excite`) is allowed, and
            writing through a symbolic link at ``path`` (the file it points to is written).
        exists_ok: an existing file is expected (a result to resume).

    Returns:
        ``path``.

    Raises:
        OutputExists: the file exists, or a symbolic link is there, and neither ``force`` nor ``exists_ok``.
        ExciteError: ``path`` is a folder or not a regular file (a device, a FIFO), a file excite did not
            write (with ``force``), a loop of symbolic links, a file is in the way of its folder, or its
            nearest existing folder is not writable.
    """
    path = Path(path)
    if path.is_symlink():
        try:
            target = path.resolve()  # the file it points to is what is written
        except (RuntimeError, OSError):
            raise ExciteError(field, f"{path} is a loop of symbolic links", path, "a file name") from None
        if not (force or exists_ok):
            raise OutputExists(field, path)
        path = target
    if path.is_dir():
        raise ExciteError(field, f"{path} is a folder", path, "a file name")
    if path.exists() and not path.is_file():  # a device, FIFO or socket is never replaced, even with --force
        raise ExciteError(field, f"{path} is not a regular file", path, "a file name")
    if path.exists() and not (force or exists_ok):
        raise OutputExists(field, path)
    if path.exists() and force and not exists_ok and not written_by_excite(path):
        raise ExciteError(
            field,
            f"{path} exists and excite did not write it (it holds no mark of excite's); not replaced",
            path,
            "another path, or remove that file yourself",
        )
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
