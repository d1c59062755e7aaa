"""The model and the fit that transfer, chosen together by the selection's own cross-validation.

Least squares of a model fits the fit data best; on poorly exciting data its base parameters are
free to take values no robot has and extrapolate badly to motions the fit did not see. The
physically consistent fit (:mod:`~excite_cli.identification.fitting.physical`) keeps every body a real mass
distribution and, with weight λ, near the CAD model; on well-excited data it costs a little. Which
one transfers depends on the data set, and so do the effects a model needs: the effect search runs
under least squares with the consistent fit's bounds on friction and armature
(:mod:`~excite_cli.identification.choice.selection`), where an effect may stand in for base
parameters the data leave free, which the consistent fit pins. So each search's start and end are
scored under every candidate fit on the folds that chose the effects (the same margins and held-out
offsets) under the search's own admission rule (:mod:`~excite_cli.identification.choice.admission`):
least squares (its CV error is the search's) and the consistent fit at every λ of
``identification.regularization``, refitted on each fold's training normal equations.

**Folds of distinct recordings** (the paired test): each pair's J(M, fit) is its mean log fold error;
of the consistent pairs (each model's lowest J) a model with more effects is kept only when it beats
the kept one by the paired test, and that pair is reported unless least squares, chosen among models
the same way, beats it by the test too (then least squares, with the consistent fit beside it).

**Time blocks** (the price): the search's own objective

    J(M, fit) = log CV(M, fit) + p(M) · log(1 + min_improvement) [+ log(1 + least_squares_margin)],

p(M) the effects M adds beyond the declared ones. A consistent fit holds every joint's rotor
(:mod:`~excite_cli.identification.choice.consistent_model`), so a model's armature terms change
nothing in it and are not in its p(M): models that differ only by them tie, and the first compared
(the kept search's end) is kept with the effects the search found. Least squares pays the bracketed
price when a consistent fit is a candidate: it must cut the CV error of the consistent fit by the
fraction ``least_squares_margin`` (default 0.5) to be chosen. Time blocks see motion next to the fit's,
which does not charge least squares for base-parameter directions such motion barely excites and a
new motion does (the real Panda's first 20 %: 6.89 % CV against 9.23 %, 9.89 % against 7.61 % on
the rest; docs/figures.md, "Which fit transfers"). The pair with the lowest J wins (``fit: auto``).
``fit: least_squares`` or ``consistent`` restricts the fits (least squares alone keeps the search's
model); a single pair is not cross-validated. The reported model, its validation error and the identified
URDF are the winner's; the best consistent fit of the winning model stays beside least squares.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.robot import Robot
from excite_cli.identification.choice.admission import Admission, effect_count, paired_choice, priced_objective
from excite_cli.identification.choice.consistent_model import ConsistentModel
from excite_cli.identification.choice.fit_records import LEAST_SQUARES, FitChoice, Model
from excite_cli.identification.choice.selection import Selection
from excite_cli.identification.config import IdentificationConfig
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.least_squares import least_squares


def candidates(cfg: IdentificationConfig) -> list[float | None]:
    """The candidate fits of ``identification.fit``: None for least squares, λ for a consistent fit."""
    plain = [] if cfg.fit == "consistent" else [None]
    return plain + ([] if cfg.fit == "least_squares" else list(cfg.regularization))


def compared_models(selection: Selection) -> list[Model]:
    """The end and the start of every search, each set of terms once, the kept search's end first."""
    order = [selection.chosen] + [k for k in range(len(selection.searches)) if k != selection.chosen]
    out: list[Model] = []
    for k in order:
        search = selection.searches[k]
        for at_start, terms in ((False, search.terms), (True, search.initial)):
            if all(set(terms) != set(m.terms) for m in out):
                p = effect_count(list(terms), selection.declared, selection.effect_weights)
                rotors = len(terms[selection.declared :]) - len(_without_rotors(terms[selection.declared :]))
                out.append(Model(k, search.start, at_start, list(terms), p, rotors))
    return out


def _without_rotors(terms: list[Term]) -> frozenset[Term]:
    """``terms`` but a joint's own armature: what tells apart consistent fits (they hold every rotor)."""
    return frozenset(t for t in terms if t.effect != "armature" or t.coupling is not None)


def _scores(
    selection: Selection, model: Model, lams: list[float | None], programs: dict, known: dict
) -> tuple[np.ndarray, np.ndarray]:
    """(f,) CV error [%] and (f, K) fold errors [%] of ``model`` under each fit of ``lams`` (the
    search's own for least squares); a consistent fit's once per set of terms without rotors
    (``programs``, ``known``: its scores)."""
    search, cv, key = selection.searches[model.search], selection.cross_validation, _without_rotors(model.terms)
    out, folds = [], []
    for lam in lams:
        if lam is None:
            out.append(search.initial_error if model.at_start else search.cv_error)
            folds.append(search.initial_folds if model.at_start else search.folds)
            continue
        if (key, lam) not in known:
            consistent = programs[key]

            def refit(k: int, lam: float = lam) -> np.ndarray:
                return consistent.coefficients(*cv.training_system(k, consistent.terms), lam)

            pooled, _, per_fold = cv.score(consistent.terms, refit)
            known[key, lam] = (pooled, per_fold)
        out.append(known[key, lam][0])
        folds.append(known[key, lam][1])
    return np.array(out), np.array(folds)


def _objective(
    selection: Selection,
    models: list[Model],
    lams: list[float | None],
    cv: np.ndarray,
    folds: np.ndarray | None,
    margin: float,
    paired: bool,
) -> tuple[np.ndarray, tuple[int, int]]:
    """J (m, f) of every pair and the winner (model, fit) (module docstring): under the paired test from
    the fold errors ``folds`` (m, f, K), else priced from the CV errors ``cv`` (m, f)."""
    if paired:
        J = np.log(np.maximum(folds, 1e-12)).mean(axis=2)
        sizes = np.array([[m.counted(lam is not None) for lam in lams] for m in models])
        return J, paired_choice(J, folds, [lam is not None for lam in lams], sizes)
    J = priced_objective(cv, [[m.counted(lam is not None) for lam in lams] for m in models], selection.min_improvement)
    if any(lam is not None for lam in lams):  # least squares pays its margin (module docstring)
        J = J + np.log1p(np.array([0.0 if lam is not None else margin for lam in lams]))
    return J, ((0, 0) if folds is None else np.unravel_index(int(np.nanargmin(J)), J.shape))


def kept_selection(selection: Selection, model: Model) -> Selection:
    """``selection`` with ``model`` as its chosen model: its terms, least-squares fit and CV errors."""
    if model.search == selection.chosen and not model.at_start:
        return selection
    search = selection.searches[model.search]
    return replace(
        selection,
        terms=model.terms,
        fit=least_squares(selection.normal, model.terms, selection.weights),
        cv_error=search.initial_error if model.at_start else search.cv_error,
        cv_joint=selection.cross_validation.error(model.terms)[1],
        chosen=model.search,
        at_start=model.at_start,
    )


def choose_fit(
    selection: Selection,
    robot: Robot,
    base: BaseParameters,
    offset_runs: list[str],
    cfg: IdentificationConfig,
    consistent_beside: bool = False,
    say: Callable[[str], None] | None = None,
) -> tuple[Selection, FitChoice]:
    """Score every model of :func:`compared_models` under every fit of ``cfg.fit`` on the selection's
    folds, keep the pair with the lowest J and fit the winning model's best consistent λ on all fit
    data (module docstring).

    Args:
        selection: the searches, the least-squares fit, weights, normal equations and folds.
        robot, base, offset_runs: for the consistent fits (:class:`ConsistentModel`).
        cfg: ``fit``, ``regularization`` (λ, one or several) and ``least_squares_margin``; the price p
            pays is the selection's ``min_improvement``, the same the search used.
        consistent_beside: fit the consistent model (at the first λ) even when least squares is the
            only fit (the identified URDF needs one).
        say: told what is scored.

    Returns:
        The selection with the winning model as its chosen one, and the choice.

    Raises:
        ExciteError: a semidefinite program has no solution.
    """
    lams = candidates(cfg)
    models = compared_models(selection)
    single = len(models) * len(lams) == 1 and lams[0] is not None  # nothing to compare
    scored = any(lam is not None for lam in lams) and not single
    programs: dict[frozenset, ConsistentModel] = {}
    for m in models if scored else []:  # one program per set of terms without rotors: the first model's
        if _without_rotors(m.terms) not in programs:
            programs[_without_rotors(m.terms)] = ConsistentModel(m.terms, selection, robot, base, offset_runs)
    cv, folds, known = np.full((len(models), len(lams)), np.nan), None, {}
    if not single:
        if say:
            say(
                f"scoring fits: {len(models)} models under {len(lams)} fits on {selection.cross_validation.folds} folds"
            )
        cv, folds = (np.array(x) for x in zip(*[_scores(selection, m, lams, programs, known) for m in models]))
    paired = selection.admission is Admission.PAIRED and not single
    J, (win, chosen) = _objective(selection, models, lams, cv, folds, cfg.least_squares_margin, paired)
    consistent = [k for k, lam in enumerate(lams) if lam is not None]
    margin = cfg.least_squares_margin if consistent and None in lams and not paired else 0.0
    best = min(consistent, key=lambda k: np.nan_to_num(cv[win, k], nan=np.inf)) if consistent else None
    lam = lams[best] if best is not None else (cfg.regularization[0] if consistent_beside else None)
    fit = None
    if lam is not None:
        program = programs.get(_without_rotors(models[win].terms))
        if program is None or program.model != models[win].terms:
            program = ConsistentModel(models[win].terms, selection, robot, base, offset_runs)
        G, c, _ = selection.normal.system(selection.weights, program.terms)
        fit = program.fit(G, c, selection.normal.rows, lam)
    choice = FitChoice(
        models=models,
        names=[LEAST_SQUARES if lam is None else f"consistent λ={lam:g}" for lam in lams],
        regularization=np.array([np.nan if lam is None else lam for lam in lams]),
        cv=cv,
        objective=J,
        model=int(win),
        chosen=int(chosen),
        consistent=fit,
        margin=margin,
        admission=selection.admission,
    )
    return kept_selection(selection, models[win]), choice
