"""The ``data.columns`` of an identify draft, recognized in the user's own file: time, q, q̇ and τ of each
active joint under the names recorders commonly write (``q_<joint>``, ``<joint>_pos``, ``effort_<joint>``,
excite's own export columns ``q_<joint>_rad`` …), matched without regard to case."""

from __future__ import annotations

from typing import Optional, Sequence

#: Column name patterns per signal, ``{j}`` the joint's name, in the order they are tried.
PATTERNS = {
    "time": ["time", "time_s", "t", "timestamp", "stamp"],
    "q": ["q_{j}", "q_{j}_rad", "pos_{j}", "position_{j}", "{j}_q", "{j}_pos", "{j}_position"],
    "qd": ["qd_{j}", "qd_{j}_rad_s", "dq_{j}", "vel_{j}", "velocity_{j}", "{j}_qd", "{j}_vel", "{j}_velocity"],
    "tau": ["tau_{j}", "tau_{j}_nm", "effort_{j}", "torque_{j}", "{j}_tau", "{j}_effort", "{j}_torque"],
}


def recognized_columns(names: Sequence[str], joints: Sequence[str]) -> dict[str, object]:
    """``data.columns`` from a file's column ``names`` for the active ``joints`` (n,): ``time`` (a name)
    and ``q``, ``tau`` (n names each) where every joint's is found, ``qd`` too where every joint has one;
    a signal not found for every joint is left out.

    Returns:
        {signal: name or [names]}, possibly empty.
    """
    lower = {name.lower(): name for name in names}
    columns: dict[str, object] = {}
    time = _find(lower, PATTERNS["time"], "")
    if time is not None:
        columns["time"] = time
    for signal in ("q", "qd", "tau"):
        found = [_find(lower, PATTERNS[signal], joint) for joint in joints]
        if all(found):
            columns[signal] = found
    return columns


def _find(lower: dict[str, str], patterns: list[str], joint: str) -> Optional[str]:
    """The file's name (as written) of the first pattern that names a column, or None."""
    for pattern in patterns:
        name = lower.get(pattern.format(j=joint).lower())
        if name is not None:
            return name
    return None
