"""The one exception type that reaches the user as a one-line message (no traceback)."""


class ExciteError(Exception):
    """Bad input or an infeasible problem, worded for the user.

    The command line prints ``str(error)`` on one line and exits with status 2.
    """


class Interrupted(Exception):
    """Ctrl-C during a run that writes as it goes; ``kept`` finished parts are in ``path``."""

    def __init__(self, path, kept: int):
        super().__init__(f"interrupted: kept {kept} finished iteration(s) in {path}")
        self.path, self.kept = path, kept
