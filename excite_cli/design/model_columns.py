"""The identification model a design is for, beyond the rigid body's base parameters: the effect
columns beside the base columns (``effects``, ``effects.model``) and, when ``sequence.prior`` is an identify
report, how its measured rows weigh (:mod:`~excite_cli.stored.design_model`)."""

from __future__ import annotations

import numpy as np

from excite_cli.config import EffectsConfig
from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.effect_columns import EffectColumns, effect_columns
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.stored.design_model import MeasuredPrior, measured_prior_of, with_report_model
from excite_cli.stored.inputs import StoredInputs
from excite_cli.stored.prior import PriorFile


def measured_prior(prior: PriorFile | None, robot: Robot) -> MeasuredPrior | None:
    """How ``sequence.prior`` (``prior``, read once) weighs when it is an identify report (else None).

    Raises:
        ExciteError: (``sequence.prior``) a report whose joints are not this problem's active joints, or
            that no weighing can use (:func:`measured_prior_of`).
    """
    if prior is None or prior.report is None:
        return None
    measured = measured_prior_of(prior.report, prior.path)
    if sorted(measured.joints) != sorted(robot.joint_names):
        raise ExciteError(
            "sequence.prior",
            f"{prior.path} identified the joints {', '.join(measured.joints)}; this problem's active joints are "
            f"{', '.join(robot.joint_names)}",
        )
    return measured


def design_effects(
    cfg: EffectsConfig, stored: StoredInputs, robot: Robot, base: BaseParameters
) -> EffectColumns | None:
    """The effect columns of ``effects`` (``cfg``, with the report of ``effects.model`` read once in
    ``stored``) that the rigid body's base columns do not already hold (on random states:
    :meth:`~excite_cli.dynamics.effect_columns.EffectColumns.beside`), or None.

    Raises:
        ExciteError: an effect on a joint that is not active (:func:`effect_columns`), an
            ``effects.model`` report of other joints than this problem's.
    """
    if stored.model is not None:
        cfg = with_report_model(cfg, stored.model, stored.model_path, robot.joint_names)
    effects = effect_columns(cfg, robot.joint_names, robot.n_rows)
    if effects is None:
        return None
    count = max(50, -(-(base.count + effects.count) * 2 // robot.n_rows))
    Q, QD, QDD = robot.random_states(count, np.random.default_rng(0))
    effects = effects.beside(robot.regressor_stack(Q, QD, QDD)[:, base.independent], QD, QDD)
    return effects if effects.count else None
