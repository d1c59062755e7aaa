"""What a computation gave at the last point it was asked for: a solver asks for the value and then
the gradient, a constraint's values and then its Jacobian, at the same point, and a line search's
next trial point is a new one, so one point per computation is all a memo needs to hold."""

from __future__ import annotations

from typing import Callable, TypeVar

import numpy as np

T = TypeVar("T")


def once(owner: object, name: str, point: np.ndarray, compute: Callable[[], T]) -> T:
    """``compute()``, or what it gave when ``owner`` last asked for ``name`` at the same ``point`` (the
    same shape, dtype and bytes). Each (owner, name) holds one point, in the owner's ``_memo``
    attribute, made on first use (no constructor needs to know; a copy made by
    ``dataclasses.replace`` starts empty)."""
    memo = vars(owner).setdefault("_memo", {})
    key = (point.shape, point.dtype.str, point.tobytes())
    held = memo.get(name)
    if held is None or held[0] != key:
        held = memo[name] = (key, compute())
    return held[1]
