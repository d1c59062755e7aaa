"""Input files checked before anything opens them: every file excite reads (a config, an effects
file, a URDF, a result, a report, prior data, a measured-data file) goes through :func:`input_file`
first, so a missing file, a folder, a FIFO, a device or a file without read permission is one line
naming the argument or config field, and never a hang (reading a FIFO waits for a writer) or a
library's traceback."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from excite_cli.errors import ExciteError, FileNotFound


def input_file(path: Path | str, field: str, what: str = "file") -> Path:
    """``path`` after checking that it is a regular file this process may read (links followed).

    Args:
        path: the file given.
        field: the argument or config field that named it (``config``, ``data.runs``), for the message.
        what: what the file is, in words (``config file``, ``URDF``), for the message.

    Returns:
        ``path`` as a :class:`~pathlib.Path`.

    Raises:
        FileNotFound: nothing at ``path`` (or a link that leads nowhere).
        ExciteError: a folder, not a regular file (a FIFO, a device or a socket), or not readable.
    """
    path, expected = Path(path), f"{'an' if what.startswith(('HDF', 'a', 'e', 'i', 'o')) else 'a'} {what}"
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        raise FileNotFound(field, path, what) from None
    except OSError as exc:
        raise ExciteError(field, f"cannot read {path}: {exc.strerror}", path, expected) from None
    if stat.S_ISDIR(mode):
        raise ExciteError(field, f"{path} is a folder", path, expected)
    if not stat.S_ISREG(mode):
        kind = "a FIFO" if stat.S_ISFIFO(mode) else "a socket" if stat.S_ISSOCK(mode) else "a device"
        raise ExciteError(field, f"{path} is {kind}, not a regular file", path, expected)
    if not os.access(path, os.R_OK):
        raise ExciteError(field, f"cannot read {path} (permission denied)", path, expected)
    return path
