"""What a search of :mod:`~excite_cli.identification.choice.search` leaves: each step taken with the
moves it tried, the move the family test refused at the last step, and each start's end."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from excite_cli.identification.effects import Term

#: How a move is written: added, removed, shape changed.
MOVE_SIGNS = {"add": "+", "remove": "−", "shape": "~"}


@dataclass(frozen=True)
class Step:
    """One move of the search.

    Attributes:
        move: ``add``, ``remove`` or ``shape`` (a Stribeck or held term's velocity changed).
        term: the term added, removed, or the new shape's term.
        terms: the model after the move.
        cv_error: CV(M) [%] after the move; before: CV(M) [%] before it.
        tried: every move considered at this step: (move, term, CV after [%]).
        fold_gain, fold_margin: under the paired test, the move's mean gain over the folds and the
            margin it passed, as cuts of the error [%] (NaN under the price).
        family_margin: from :data:`~excite_cli.identification.choice.admission.FAMILY_FOLDS` folds on,
            the move's margin tested together with the step's other moves (the family-wise error), as a
            cut of the error [%]: the step was open because some move's gain exceeded its own (NaN
            below those folds, for a removal, which keeps the plain test, and under the price).
        clear_of_zero: a removal because the term's estimate was not clear of zero in the reported fit
            (:mod:`~excite_cli.identification.choice.estimates`), or a friction term added back because
            it was: its clearest coefficient's |value| in standard deviations (NaN for every other step).
    """

    move: str
    term: Term
    terms: list[Term]
    cv_error: float
    before: float
    tried: list[tuple[str, Term, float]]
    fold_gain: float = float("nan")
    fold_margin: float = float("nan")
    family_margin: float = float("nan")
    clear_of_zero: float = float("nan")

    def gain_of(self, cv_error: float) -> float:
        """The cut [%] of the CV error before this step that a move to ``cv_error`` [%] makes."""
        return 100.0 * (1.0 - cv_error / self.before)

    @property
    def gain(self) -> float:
        """The cut [%] of the CV error this step made."""
        return self.gain_of(self.cv_error)

    def label(self, joints: list[str]) -> str:
        """e.g. ``+ held panda_joint7 (v_h 0.1 rad/s)``."""
        return f"{MOVE_SIGNS[self.move]} {self.term.label(joints)}"


class Refused(NamedTuple):
    """The best addition or shape change of the last step that passed its own paired test but not the
    family's (:meth:`~excite_cli.identification.choice.search.StepwiseSearch.gate`): its gain over the
    folds, its own margin and its margin tested together with the step's ``tried`` additions and
    shape changes, as cuts of the error [%]."""

    move: str
    term: Term
    gain: float
    margin: float
    family_margin: float
    tried: int

    def label(self, joints: list[str]) -> str:
        """The refusal in words, e.g. ``+ armature j4 gains 0.41 % over the folds, ...``."""
        return (
            f"{MOVE_SIGNS[self.move]} {self.term.label(joints)} gains {self.gain:.2f} % over the folds, above its own "
            f"margin {self.margin:.2f} % but not the {self.family_margin:.2f} % of the {self.tried} moves tested "
            "together (family-wise, 95 %)"
        )


@dataclass
class Search:
    """The search from one start: its name, start model and its CV error [%], end model and its CV
    error [%] and objective J, the steps and why it stopped; the start's and the end's (K,) fold
    errors [%]; the move the family test refused at the last step (:class:`Refused`), if any."""

    start: str
    initial: list[Term]
    initial_error: float
    terms: list[Term]
    cv_error: float
    objective: float
    steps: list[Step] = field(default_factory=list)
    stop: str = ""
    initial_folds: np.ndarray | None = None
    folds: np.ndarray | None = None
    refused: Refused | None = None
