"""What the choice of the model and the fit compared and chose
(:mod:`~excite_cli.identification.choice.fit_choice`): each model scored with the fits, and the
models, fits, scores and winner."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from excite_cli.identification.choice.admission import Admission
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.physical import ConsistentFit

#: The name of the least-squares candidate.
LEAST_SQUARES = "least squares"


@dataclass(frozen=True)
class Model:
    """A model scored with the fits: the search it comes from, whether it is that search's start or
    end, its terms, the number of effects it adds beyond the declared ones (p, a coupled one
    counting as several: :func:`~excite_cli.identification.choice.selection.effect_count`) and how
    many of those are a joint's armature, which a consistent fit holds anyway (its rotors:
    :mod:`~excite_cli.identification.choice.consistent_model`) and which there add nothing to pay for."""

    search: int
    start: str
    at_start: bool
    terms: list[Term]
    effects: float
    rotors: int = 0

    def counted(self, consistent: bool) -> float:
        """p of J under a least-squares or a consistent fit (which does not count armature)."""
        return self.effects - (self.rotors if consistent else 0)

    @property
    def label(self) -> str:
        """e.g. ``end of 'Coulomb on every joint'``."""
        return f"{'start' if self.at_start else 'end'} of '{self.start}'"


@dataclass(frozen=True)
class FitChoice:
    """The models and fits compared and the pair chosen.

    Attributes:
        models: (m,) each model compared (the ends and starts of the searches, each set of terms once).
        names: (f,) each candidate fit: ``least squares`` or ``consistent λ=<λ>``.
        regularization: (f,) λ of each consistent candidate (NaN for least squares).
        cv: (m, f) CV error [%] of each model under each fit on the selection's folds (NaN: the only
            pair, not cross-validated).
        objective: (m, f) J of each pair (module docstring).
        model: index of the winning model in ``models``; chosen: index of its fit in ``names``.
        consistent: the physically consistent fit of the winning model on all fit data at its best
            consistent λ (the winner's, or the one beside least squares), or None when none was asked for.
        margin: the fraction least squares had to cut the consistent fit's CV error by (0: none or
            the paired test).
        admission: the rule the pairs were compared by (the search's).
    """

    models: list[Model]
    names: list[str]
    regularization: np.ndarray
    cv: np.ndarray
    objective: np.ndarray
    model: int
    chosen: int
    consistent: ConsistentFit | None
    margin: float = 0.0
    admission: Admission = Admission.PRICED

    @property
    def name(self) -> str:
        """The winning fit's name."""
        return self.names[self.chosen]

    @property
    def is_consistent(self) -> bool:
        """Whether the winning fit is a physically consistent one."""
        return self.name != LEAST_SQUARES

    @property
    def labels(self) -> list[str]:
        """(m,) the models' labels, e.g. ``end of 'declared effects'``."""
        return [m.label for m in self.models]

    @property
    def cv_error(self) -> np.ndarray:
        """(f,) CV error [%] of the winning model under each fit."""
        return self.cv[self.model]

    def effects(self, model: int, fit: int) -> float:
        """p of J: the effects ``models[model]`` adds, counted under the fit ``names[fit]`` (a consistent
        fit does not count armature: module docstring)."""
        return self.models[model].counted(self.names[fit] != LEAST_SQUARES)

    @property
    def lead(self) -> float:
        """How much lower the winner's CV error is than the next best fit's of the same model [% points]
        (NaN with a single fit)."""
        others = np.delete(self.cv_error, self.chosen)
        if others.size == 0 or np.all(np.isnan(others)):
            return float("nan")
        return float(np.nanmin(others) - self.cv_error[self.chosen])
