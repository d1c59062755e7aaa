"""The one exception type that reaches the user as a one-line message (no traceback)."""


class ExciteError(Exception):
    """Bad input or an infeasible problem, worded for the user.

    The command line prints ``str(error)`` on one line and exits with status 2.
    """
