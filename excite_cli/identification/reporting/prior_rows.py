"""An identify report's rows as the next design's prior data: the base regressor of the fit and
validation samples, and the columns of the chosen effects a design holds (named as a design names
them), which the report file writes and :func:`~excite_cli.stored.prior.prior_rows` weighs as
identification did (the paper's prior data C₀, Eq. 41)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from excite_cli.dynamics.effect_columns import coefficient_name
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import predict


@dataclass
class PriorRows:
    """An identify report's rows as prior data: the base regressor and the design's effect columns of
    the same samples, in parts (fit, then validation), which the report file writes and empties.

    Attributes:
        regressor: (M_k, b) base regressor rows per part.
        effects: (M_k, e) effect columns per part, named ``effect_names`` as a design names them
            (:func:`~excite_cli.dynamics.effect_columns.effect_columns`: ``Fc_panda_joint4``,
            ``Ia_motor_wrist_2+wrist_3``).
        effect_names: (e,) the names.
        predicted: (M_k,) the reported model's torque [Nm] of each row per part, what the rows' noise
            grows with (:meth:`~excite_cli.stored.design_model.MeasuredPrior.row_weights`).
    """

    regressor: list[np.ndarray]
    effects: list[np.ndarray]
    effect_names: list[str]
    predicted: list[np.ndarray]


def _design_names(term: Term, joints: list[str]) -> list[str] | None:
    """The design's names of ``term``'s columns, or None for an effect a design does not hold (module
    docstring) or a coupled joint effect (the design couples only motors)."""
    if term.kind.parts:  # a motor: its columns are its parts', in that order
        return [coefficient_name(kind, [joints[j] for j in term.joints], motor=True) for kind in term.kind.parts]
    if term.kind.designed and term.coupling is None:
        return [coefficient_name(term.effect, [joints[term.joint]])]
    return None


def prior_rows(parts: list[Dataset], terms: list[Term], joints: list[str], model: tuple) -> PriorRows:
    """The rows of ``parts`` (the identification's fit and validation data) as prior data: their base
    regressor, and the columns of the chosen ``terms`` a design holds, taken from the parts' own
    low-passed and decimated effect blocks (the columns identification fitted, weighed as it weighed
    them), an offset as one column of ones on its joint's rows (the design's, not one per run).

    Args:
        parts: datasets with the blocks of ``terms``; joints: the active joints (n), in the rows' order.
        model: the reported model, its coefficients x (base parameters first) and terms: each row's
            predicted torque.

    Returns:
        Per part, (M_k, b) base regressor rows and (M_k, e) effect columns: the prior data C₀ of the
        paper's sequential generation (Eq. 41) once :func:`~excite_cli.stored.prior.prior_rows` weighs
        them as identification did.
    """
    names: list[str] = []
    columns: list[list[np.ndarray]] = [[] for _ in parts]
    for term in terms:
        named = _design_names(term, joints)
        if named is None:
            continue
        names += named
        for out, data in zip(columns, parts):
            if term.kind.per_run:  # the design's offset: one column of ones, not one per run
                block = np.zeros((data.tau.size, 1))
                block[term.joint :: data.n] = 1.0
            else:
                block = data.block(term)
            out.append(block)
    effects = [np.hstack(c) if c else np.zeros((d.tau.size, 0)) for c, d in zip(columns, parts)]
    predicted = [predict(d, *model).ravel() for d in parts]  # what each row's noise grows with
    return PriorRows([d.regressor for d in parts], effects, names, predicted)
