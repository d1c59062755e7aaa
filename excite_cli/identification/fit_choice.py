"""The fit that transfers, chosen by the selection's own cross-validation.

Least squares of the chosen model fits the fit data best; on poorly exciting data its base
parameters are free to take values no robot has and extrapolate badly to motions the fit did not
see. The physically consistent fit (:mod:`~excite_cli.identification.physical`) of the same model
keeps every body a real mass distribution and, with weight λ, near the CAD model; on well-excited
data it costs a little. Which one transfers depends on the data set, so the candidates are scored on
the folds that chose the effects (:class:`~excite_cli.identification.crossval.CrossValidation`:
whole runs or time blocks, the same margins and held-out offsets): least squares (its CV error is
the selection's) and the consistent fit at every λ of ``identification.regularization``, refitted
on each fold's training normal equations. The lowest CV error wins (``fit: auto``); ``fit:
least_squares`` or ``consistent`` restricts the candidates, and a single candidate is not
cross-validated. The reported model, its validation error and the identified URDF are the
winner's; the best consistent fit stays beside least squares in the report.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.robot import Robot
from excite_cli.identification.config import IdentificationConfig
from excite_cli.identification.effects import coefficient_names
from excite_cli.identification.physical import ConsistentFit, ConsistentProgram
from excite_cli.identification.selection import Selection

#: The name of the least-squares candidate.
LEAST_SQUARES = "least squares"


@dataclass(frozen=True)
class FitChoice:
    """The fits compared and the one chosen.

    Attributes:
        names: (f,) each candidate: ``least squares`` or ``consistent λ=<λ>``.
        regularization: (f,) λ of each consistent candidate (NaN for least squares).
        cv_error: (f,) CV error [%] of each on the selection's folds (NaN: the only candidate).
        chosen: index of the winner in ``names``.
        consistent: the physically consistent fit on all fit data at the best consistent λ (the
            winner's, or the one beside least squares), or None when none was asked for.
    """

    names: list[str]
    regularization: np.ndarray
    cv_error: np.ndarray
    chosen: int
    consistent: ConsistentFit | None

    @property
    def name(self) -> str:
        """The winner's name."""
        return self.names[self.chosen]

    @property
    def is_consistent(self) -> bool:
        """Whether the winner is a physically consistent fit."""
        return self.name != LEAST_SQUARES

    @property
    def lead(self) -> float:
        """How much lower the winner's CV error is than the next best candidate's [% points]
        (NaN with a single candidate)."""
        others = np.delete(self.cv_error, self.chosen)
        if others.size == 0 or np.all(np.isnan(others)):
            return float("nan")
        return float(np.nanmin(others) - self.cv_error[self.chosen])


class ConsistentModel:
    """The physically consistent fit of a selected model, on any normal equations of its unknowns
    [Y_B, ``selection.terms``] (all fit data, or one fold's training data): one compiled program.

    Args:
        selection: the chosen terms and the fit data's normal equations; robot, base: the URDF's
            parameters, bodies and regrouping K.
        offset_runs: the labels of the fitted runs, which name the offsets' columns.
    """

    def __init__(self, selection: Selection, robot: Robot, base: BaseParameters, offset_runs: list[str]):
        names = [
            f"{name} {robot.joint_names[t.joint]}"
            for t in selection.terms
            for name in coefficient_names(t, offset_runs)
        ]
        reference = selection.normal.system(selection.weights, selection.terms)[0]
        self.program = ConsistentProgram(reference, base.regrouping, robot.urdf_parameters(), names, robot.body_names)

    def fit(self, G: np.ndarray, c: np.ndarray, rows: int, regularization: float) -> ConsistentFit:
        """The SDP of :class:`ConsistentProgram` on the weighted normal equations G, c of ``rows`` rows.

        Raises:
            ExciteError: the semidefinite program has no solution.
        """
        return self.program.solve(G, c, rows, regularization)

    def coefficients(self, G: np.ndarray, c: np.ndarray, rows: int, regularization: float) -> np.ndarray:
        """(b + k,) the fit's base parameters and effect coefficients, in the model's unknowns."""
        fit = self.fit(G, c, rows, regularization)
        return np.concatenate([fit.base, fit.effects])


def candidates(cfg: IdentificationConfig) -> list[float | None]:
    """The candidate fits of ``identification.fit``: None for least squares, λ for a consistent fit."""
    plain = [] if cfg.fit == "consistent" else [None]
    return plain + ([] if cfg.fit == "least_squares" else list(cfg.regularization))


def choose_fit(
    selection: Selection,
    model: ConsistentModel,
    cfg: IdentificationConfig,
    consistent_beside: bool = False,
) -> FitChoice:
    """Score the candidate fits of ``cfg.fit`` on the selection's folds and fit the best consistent
    one on all fit data (module docstring).

    Args:
        selection: the chosen model, its least-squares fit, weights, normal equations and folds.
        model: its physically consistent fit.
        cfg: ``fit`` and ``regularization`` (λ, one or several).
        consistent_beside: fit the consistent model (at the first λ) even when least squares is the
            only candidate (the identified URDF needs one).

    Raises:
        ExciteError: a semidefinite program has no solution.
    """
    lams = candidates(cfg)
    cv = selection.cross_validation
    errors = np.full(len(lams), np.nan)
    for i, lam in enumerate(lams if len(lams) > 1 else []):
        if lam is None:
            errors[i] = selection.cv_error
            continue

        def refit(k: int, lam: float = lam) -> np.ndarray:
            return model.coefficients(*cv.training_system(k, selection.terms), lam)

        errors[i] = cv.error(selection.terms, refit)[0]
    chosen = int(np.nanargmin(errors)) if len(lams) > 1 else 0
    consistent = [(errors[i], i) for i, lam in enumerate(lams) if lam is not None]
    best = lams[min(consistent)[1]] if consistent else (cfg.regularization[0] if consistent_beside else None)
    fit = None
    if best is not None:
        G, c, _ = selection.normal.system(selection.weights, selection.terms)
        fit = model.fit(G, c, selection.normal.rows, best)
    return FitChoice(
        names=[LEAST_SQUARES if lam is None else f"consistent λ={lam:g}" for lam in lams],
        regularization=np.array([np.nan if lam is None else lam for lam in lams]),
        cv_error=errors,
        chosen=chosen,
        consistent=fit,
    )
