"""The identification model a design is for, beyond the rigid body's base parameters: the effect
columns beside the base columns (``effects``, ``effects.model``) and, when ``sequence.prior`` is an identify
report, how its measured rows weigh (:mod:`~excite_cli.stored.design_model`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from excite_cli.config import EffectsConfig, resolve_path
from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.effect_columns import EffectColumns, effect_columns
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.stored.design_model import MeasuredPrior, measured_prior_of, with_report_model
from excite_cli.stored.report import read_report


def measured_prior(path: str | None, folder: Path | None, robot: Robot) -> MeasuredPrior | None:
    """How ``sequence.prior`` (``path``, relative to ``folder``) weighs when it is an identify report
    (else None).

    Raises:
        ExciteError: (``sequence.prior``) a report whose joints are not this problem's active joints, or
            that no weighing can use (:func:`read_report`, :func:`measured_prior_of`).
    """
    found = None if path is None else resolve_path(path, folder)
    report = None if found is None else read_report(found, "sequence.prior")
    if report is None:
        return None
    measured = measured_prior_of(report, found)
    if sorted(measured.joints) != sorted(robot.joint_names):
        raise ExciteError(
            "sequence.prior",
            f"{path} identified the joints {', '.join(measured.joints)}; this problem's active joints are "
            f"{', '.join(robot.joint_names)}",
        )
    return measured


def design_effects(cfg: EffectsConfig, folder: Path | None, robot: Robot, base: BaseParameters) -> EffectColumns | None:
    """The effect columns of ``effects`` (``cfg``, its model file relative to ``folder``) that the rigid
    body's base columns do not already hold (on random states:
    :meth:`~excite_cli.dynamics.effect_columns.EffectColumns.beside`), or None.

    Raises:
        ExciteError: an effect on a joint that is not active (:func:`effect_columns`), an
            ``effects.model`` that is not an identify report of this problem's joints.
    """
    if cfg.model is not None:
        cfg = with_report_model(cfg, resolve_path(cfg.model, folder), robot.joint_names)
    effects = effect_columns(cfg, robot.joint_names, robot.n_rows)
    if effects is None:
        return None
    count = max(50, -(-(base.count + effects.count) * 2 // robot.n_rows))
    Q, QD, QDD = robot.random_states(count, np.random.default_rng(0))
    effects = effects.beside(robot.regressor_stack(Q, QD, QDD)[:, base.independent], QD, QDD)
    return effects if effects.count else None
