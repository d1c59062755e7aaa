"""The constraint rows a solver sees: where a problem has more rows than ``SCREEN_ROWS``, the solver gets
a fixed number of them (its QP's cost grows with the rows: scipy's SLSQP spends 9 ms per iteration on
266 rows and 266 variables, 1.9 ms on 100), those that can bind.

Each of the ``SCREEN_ROWS`` slots holds one row of the problem. They start with the rows of the
largest values at the start; at every point whose values the solver asks for, a row outside with a
value above ``-ENTER`` (normalized, > 0 outside) takes the slot of the lowest row inside if that row is
lower. A row only leaves its slot for a higher one, so the rows that bind keep their slots (and the
multipliers of the solver's QP stay with them); rows far from binding never change places. A row that
is swapped out is far from binding at a point the solver may accept, so its multiplier in the
solver's quasi-Newton update of the Lagrangian is zero.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

#: Problems with more constraint rows than this hand the solver this many.
SCREEN_ROWS = 128
#: A row outside the slots whose value is above −ENTER [1, normalized] enters, in place of the lowest.
ENTER = 1.0


class Rows(Protocol):
    """What is screened: a problem's criterion and its stacked constraint rows in z."""

    def value(self, z: np.ndarray) -> float: ...

    def gradient(self, z: np.ndarray) -> np.ndarray: ...

    def constraint_values(self, z: np.ndarray) -> np.ndarray: ...

    def constraint_jacobian(self, z: np.ndarray) -> np.ndarray: ...


class Screened:
    """``nlp`` with at most ``SCREEN_ROWS`` of its constraint rows (module docstring); the criterion as
    it is.

    Args:
        nlp: the problem (its value, gradient, constraint values (m,) and Jacobian (m, n_z)).
        z0: (n_z,) the start, whose values fill the slots.
    """

    def __init__(self, nlp: Rows, z0: np.ndarray):
        self.nlp, self.value, self.gradient = nlp, nlp.value, nlp.gradient
        values = nlp.constraint_values(z0)
        self.slots = np.sort(np.argsort(-values, kind="stable")[:SCREEN_ROWS])
        self._at: bytes | None = None

    def constraint_values(self, z: np.ndarray) -> np.ndarray:
        """The slots' values (k,) at z, after any row outside that can bind took a slot."""
        values = self.nlp.constraint_values(z)
        inside = np.zeros(values.size, dtype=bool)
        inside[self.slots] = True
        outside = np.flatnonzero(~inside & (values > -ENTER))  # rows that can bind, not in a slot
        for row in outside[np.argsort(-values[outside])]:
            lowest = int(np.argmin(values[self.slots]))
            if values[self.slots[lowest]] >= values[row]:
                break
            self.slots[lowest] = row
        self._at = z.tobytes()
        return values[self.slots]

    def constraint_jacobian(self, z: np.ndarray) -> np.ndarray:
        """The slots' Jacobian (k, n_z) at z, the slots of the last point whose values were asked for."""
        if self._at != z.tobytes():
            self.constraint_values(z)
        return self.nlp.constraint_jacobian(z)[self.slots]


def screened(nlp: Rows, z0: np.ndarray) -> Rows:
    """``nlp`` as the solver sees it: :class:`Screened` where it has more than ``SCREEN_ROWS`` constraint
    rows at z0 (n_z,), else itself."""
    return Screened(nlp, z0) if nlp.constraint_values(z0).size > SCREEN_ROWS else nlp
