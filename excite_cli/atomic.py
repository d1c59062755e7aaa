"""Files written whole or not at all: every file excite writes (HDF5, PNG, HTML, CSV, URDF) goes
through a temporary ``.<name>.partial`` beside ``<path>`` moved onto its path only when it is complete, and the folders
made for it are removed again when nothing was written; a folder written as one (a ROS 2 bag) the same way.
A path that is a symbolic link is written through: the file it points to is replaced, never the link.
Every file and folder excite writes carries :data:`MARK` (an HDF5 attribute, a PNG text chunk, a
comment line, a bag's custom data), so that ``force`` replaces only what excite wrote
(:func:`~excite_cli.storage.paths.written_by_excite`)."""

from __future__ import annotations

import os
import re
import shutil
import warnings
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Iterator, Sequence

from excite_cli import __version__
from excite_cli.errors import CannotWrite, ExciteWarning

#: What every file and folder excite writes says of itself (with its version; in a text file also the
#: command that wrote it).
MARK_PREFIX = "written by excite"
MARK = f"{MARK_PREFIX} {__version__}"
#: A mark as excite writes it, whole: the prefix, a version and, in a text file or an NPZ, the command
#: (``written by excite 0.1.0``, ``written by excite 0.1.0 export``): not ``NOT written by excite``, not
#: ``written by excite_recorder 2.0``, not a sentence that quotes it.
MARK_VERSION = r"\d+(?:\.\d+)+(?:[-+.]?[0-9A-Za-z]+)*"
MARK_PATTERN = re.compile(rf"{MARK_PREFIX} {MARK_VERSION}(?: [a-z][a-z-]*)?")


def is_mark(text: str) -> bool:
    """Whether ``text`` is excite's mark and nothing else (:data:`MARK_PATTERN`)."""
    return MARK_PATTERN.fullmatch(text.strip()) is not None


def through_links(path: Path) -> Path:
    """``path``, or the file a symbolic link there points to (followed to its end), which a write
    replaces instead of the link.

    Raises:
        RuntimeError: a loop of symbolic links.
    """
    path = Path(path)
    return path.resolve() if path.is_symlink() else path


def partial_path(path: Path) -> Path:
    """The hidden temporary ``.<name>.partial`` beside ``path`` that :func:`atomic_paths` writes first."""
    return path.with_name(f".{path.name}.partial")


def remove_stale(path: Path) -> None:
    """Remove ``path`` (a file, or a folder with what it holds) if it exists, with an
    :class:`~excite_cli.errors.ExciteWarning` saying so (a temporary file or folder of a run that was
    killed: nothing else writes it now)."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        try:
            path.unlink()
        except FileNotFoundError:
            return
    warnings.warn(f"removed {path}, left by an interrupted run", ExciteWarning, stacklevel=2)


@contextmanager
def new_folders(paths: Sequence[Path], field: str = "output") -> Iterator[None]:
    """The folders of ``paths``, created as needed for the block; those it created that are empty
    when the block ends (an error, or nothing written into them) are removed again.

    Raises:
        CannotWrite: a folder cannot be created.
    """
    parents = [Path(p).parent for p in paths]
    created = sorted({d for f in parents for d in (f, *f.parents) if not d.exists()}, key=lambda d: -len(d.parts))
    try:
        for path, folder in zip(paths, parents):
            try:
                folder.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise CannotWrite(field, Path(path), exc.strerror or exc) from None
        yield
    finally:
        for folder in created:
            with suppress(OSError):
                folder.rmdir()


@contextmanager
def atomic_paths(paths: Sequence[Path], field: str = "output") -> Iterator[list[Path]]:
    """Temporary paths ``.<name>.partial`` beside ``<path>`` to write to, moved onto ``paths`` (``os.replace``) when the
    block ends without error and removed otherwise, with any folder made for them
    (:func:`new_folders`), so a crash, Ctrl-C or full disk never leaves a half-written file nor a
    part of the set; one a killed run left is removed first, with a warning (:func:`remove_stale`).

    Args:
        field: the config field or argument that named ``paths``, for the message.

    Raises:
        CannotWrite: a file cannot be written (``OSError`` in the block or in a move).
    """
    paths = [through_links(p) for p in paths]
    tmps = [partial_path(p) for p in paths]  # hidden: a killed run's is not in the way
    for tmp in tmps:
        remove_stale(tmp)
    try:
        with new_folders(paths, field):
            try:
                yield tmps
                for tmp, path in zip(tmps, paths):
                    os.replace(tmp, path)
            finally:
                for tmp in tmps:
                    tmp.unlink(missing_ok=True)
    except OSError as exc:
        at = next((p for p, t in zip(paths, tmps) if str(t) == str(exc.filename)), paths[0])
        raise CannotWrite(field, at, exc.strerror or exc) from None


@contextmanager
def atomic_path(path: Path, field: str = "output") -> Iterator[Path]:
    """One file written through :func:`atomic_paths`: ``.<name>.partial`` beside ``<path>`` to write to.

    Raises:
        CannotWrite: the file cannot be written.
    """
    with atomic_paths([path], field) as (tmp,):
        yield tmp


@contextmanager
def atomic_folders(paths: Sequence[Path], field: str = "output") -> Iterator[list[Path]]:
    """Folders written whole or not at all, as a set: the block fills ``.<name>.partial/<name>`` beside
    each path (the inner folder has the target's own name, for writers that name their files after
    their folder, as rosbag2 does); when it ends without error each is moved onto its path (a folder
    already there is replaced: the caller has checked that it may be), else all are removed, with any
    folder made for them (:func:`new_folders`). A folder a new one replaces is only set aside until
    every new one is in place, and all are put back if a move fails; one a killed run left is removed
    first, with a warning (:func:`remove_stale`).

    Raises:
        CannotWrite: a folder cannot be written (``OSError`` in the block or in a move).
    """
    paths = [Path(p) for p in paths]
    stagings = [partial_path(p) for p in paths]
    for staging in stagings:
        remove_stale(staging)
    try:
        with new_folders(paths, field):
            try:
                for staging in stagings:
                    staging.mkdir()
                yield [staging / path.name for staging, path in zip(stagings, paths)]
                _swap_in(paths, stagings)
            finally:
                for staging in stagings:
                    shutil.rmtree(staging, ignore_errors=True)
    except OSError as exc:
        raise CannotWrite(field, paths[0], exc.strerror or exc) from None


def _swap_in(paths: list[Path], stagings: list[Path]) -> None:
    """Each finished ``<staging>/<name>`` onto its path, the folder there set aside in the staging
    first; when a move fails, the new folders moved so far go back and every set-aside folder returns."""
    done = []
    try:
        for path, staging in zip(paths, stagings):
            done.append((path, staging))
            if path.exists():
                os.replace(path, staging / ".replaced")
            os.replace(staging / path.name, path)
    except OSError:
        for path, staging in reversed(done):
            if not (staging / path.name).exists() and path.exists():  # a new folder in place: out again
                os.replace(path, staging / path.name)
            if (staging / ".replaced").exists():
                os.replace(staging / ".replaced", path)
        raise


@contextmanager
def atomic_folder(path: Path, field: str = "output") -> Iterator[Path]:
    """One folder written through :func:`atomic_folders`: ``.<name>.partial/<name>`` beside ``path``.

    Raises:
        CannotWrite: the folder cannot be written.
    """
    with atomic_folders([path], field) as (staging,):
        yield staging


def atomic_bytes(path: Path, data: bytes | memoryview, field: str = "output") -> Path:
    """``data`` written to ``path`` through :func:`atomic_path` and flushed to the disk (``fsync``),
    so a full disk or a file-size limit is a :class:`CannotWrite` and never a half-written file.

    Raises:
        CannotWrite: the file cannot be written.
    """
    with atomic_path(path, field) as tmp:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
    return Path(path)
