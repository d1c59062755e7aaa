"""The errors that reach the user as one line (no traceback). Each names the field at fault, the
offending value and what is expected, so a caller (the command line, a notebook, a test) reads them
as data; the command line alone words the field as its option (``output`` → ``--output``). Ctrl-C and
SIGTERM stop a run the same way (:func:`sigterm_as_interrupt`)."""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

#: ``value`` when no single value is at fault (a missing entry, a relation between fields).
NO_VALUE = None


class ExciteError(Exception):
    """Bad input or an infeasible problem.

    Args:
        field: where the input came from: a config field as written in the YAML (``limits.velocity``,
            ``data.columns.torque``), or the name of the library function's argument (``output``,
            ``periods``, ``report``); never a command-line flag.
        problem: what is wrong, in words, without the field.
        value: the offending value (``NO_VALUE`` when no single value is at fault).
        expected: what would be accepted ("" when the problem says it).
        source: the file ``field`` is in, when it is a config field of a file.

    Attributes:
        status: the command line's exit status (2: bad input).
    """

    status = 2

    def __init__(self, field: str, problem: str, value: Any = NO_VALUE, expected: str = "", source: Path | None = None):
        self.field, self.problem, self.value, self.expected, self.source = field, problem, value, expected, source
        super().__init__(field, problem, value, expected)

    def describe(self, field: str | None = None, source: Path | None = None) -> str:
        """One line: ``[source: ]field: problem[; expected …]``, with ``field`` worded by the caller and
        ``source`` (the file a config field is in) given by it if the error has none."""
        tail = f"; expected {self.expected}" if self.expected else ""
        source = self.source or source
        head = f"{source}: " if source else ""
        return f"{head}{field or self.field}: {self.problem}{tail}"

    def __str__(self) -> str:
        return self.describe()


class NoSolution(ExciteError):
    """A run that could not reach a result from valid input (no restart of an optimization succeeded):
    exit status 1, as for a run that failed, not 2 as for bad input."""

    status = 1


class ExciteWarning(UserWarning):
    """What a user should know that does not stop the run (a stale temporary file removed), raised
    with :func:`warnings.warn`; the command line prints it as one line ``warning: ...``."""


class FileNotFound(ExciteError):
    """An input file that does not exist (``value``: the path)."""

    def __init__(self, field: str, path: Path | str, what: str = "file"):
        super().__init__(field, f"{what} not found: {path}", Path(path))


class OutputExists(ExciteError):
    """An output file that exists and may not be replaced (``value``: the path); the command line
    adds how to replace it."""

    def __init__(self, field: str, path: Path):
        super().__init__(field, f"{path} exists", Path(path))


class CannotWrite(ExciteError):
    """An output that cannot be written (``value``: the path; ``reason``: the system's words)."""

    def __init__(self, field: str, path: Path, reason: object):
        super().__init__(field, f"cannot write {path}: {reason}", Path(path))
        self.reason = str(reason)


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, a scheduler, a CI timeout), raised where Ctrl-C would be so that both stop a
    run the same way; ``status`` 143 (128 + SIGTERM) instead of Ctrl-C's 130."""

    status = 143


def exit_status(interrupt: KeyboardInterrupt) -> int:
    """The exit status of an interruption: 143 for SIGTERM (:class:`Terminated`), 130 for Ctrl-C."""
    return Terminated.status if isinstance(interrupt, Terminated) else 130


class Interrupted(Exception):
    """Ctrl-C or SIGTERM during a run that writes as it goes; ``kept`` finished parts are in ``path``;
    ``status`` the exit status (130 Ctrl-C, 143 SIGTERM)."""

    def __init__(self, path, kept: int, status: int = 130):
        word = "terminated" if status == Terminated.status else "interrupted"
        super().__init__(f"{word}: kept {kept} finished iteration(s) in {path}")
        self.path, self.kept, self.status = path, kept, status


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM raises :class:`Terminated` (a KeyboardInterrupt) in the main thread, so it stops a run
    as Ctrl-C does: workers stopped, partial files removed, finished work kept; a second SIGTERM
    during that clean-up is ignored."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def terminate(signum, frame) -> None:
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        raise Terminated()

    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
