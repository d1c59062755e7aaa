"""The errors that reach the user as one line (no traceback). Each names the field at fault, the
offending value and what is expected, so a caller (the command line, a notebook, a test) reads them
as data; the command line alone words the field as its option (``output`` → ``--output``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

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
    """

    def __init__(self, field: str, problem: str, value: Any = NO_VALUE, expected: str = "", source: Path | None = None):
        self.field, self.problem, self.value, self.expected, self.source = field, problem, value, expected, source
        super().__init__(field, problem, value, expected)

    def describe(self, field: str | None = None) -> str:
        """One line: ``field: problem[; expected …]``, with ``field`` worded by the caller if given."""
        tail = f"; expected {self.expected}" if self.expected else ""
        head = f"{self.source}: " if self.source else ""
        return f"{head}{field or self.field}: {self.problem}{tail}"

    def __str__(self) -> str:
        return self.describe()


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


class Interrupted(Exception):
    """Ctrl-C during a run that writes as it goes; ``kept`` finished parts are in ``path``."""

    def __init__(self, path, kept: int):
        super().__init__(f"interrupted: kept {kept} finished iteration(s) in {path}")
        self.path, self.kept = path, kept
