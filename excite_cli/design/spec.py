"""A design resolved once: what an excitation is built from, as values.

    config ─► resolve(problem) ─► DesignSpec ─► build_design(spec) ─► Excitation

Everything derived from the robot's file and the report files (the base parameters, the effect
columns, the scaling frame, the measured prior's weights) is computed once, in the main process, and
held by a frozen, picklable record; the main process and every worker (a local pool or a Dask
cluster) build their :class:`~excite_cli.design.excitation.Excitation` from that record, so a value
changed in memory (``dataclasses.replace(spec, scaled_frame=…)``) reaches every process, and no worker
computes a base of its own. The record's arrays are read-only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import block_diag

from excite_cli.config import Problem
from excite_cli.constraints.joint_limits import joint_limit_bounds
from excite_cli.design.information import parameter_magnitudes, scaled_frame
from excite_cli.design.model_columns import design_effects, measured_prior
from excite_cli.dynamics.base_parameters import BaseParameters, compute_base_parameters
from excite_cli.dynamics.effect_columns import EffectColumns
from excite_cli.dynamics.robot import Robot, load_robot
from excite_cli.identification.reporting.design_model import MeasuredPrior


@dataclass(frozen=True)
class DesignSpec:
    """What one excitation design is built from, resolved once (:func:`resolve`).

    Attributes:
        problem: the validated config.
        base: the robot's base parameters (Eq. 2).
        effects: the effect columns designed for beside the base columns (``effects``), or None.
        scaled_frame: L (b+e, b+e), read-only: C L is the regressor in a basis that does not depend on
            the choice of base columns (:func:`~excite_cli.design.information.scaled_frame`), each
            effect column scaled by its typical magnitude (:meth:`EffectColumns.magnitudes`).
        measured: how the rows of ``sequence.prior`` weigh when it is an identify report
            (:class:`~excite_cli.identification.reporting.design_model.MeasuredPrior`), or None.
    """

    problem: Problem
    base: BaseParameters
    effects: EffectColumns | None
    scaled_frame: np.ndarray
    measured: MeasuredPrior | None

    def __post_init__(self) -> None:
        frame = np.array(self.scaled_frame, dtype=float)
        frame.flags.writeable = False
        object.__setattr__(self, "scaled_frame", frame)

    @property
    def columns(self) -> int:
        """b + e: the regressor's columns, base parameters then effect columns."""
        return self.base.count + (self.effects.count if self.effects else 0)


def needs_collision(problem: Problem) -> bool:
    """Whether the robot needs its collision geometry: capsules, the soles' contact points."""
    ccfg = problem.constraints
    return bool(ccfg.self_collision or ccfg.environment or ccfg.zmp or (ccfg.com and ccfg.com.support_links))


def resolve(problem: Problem, base: BaseParameters | None = None) -> tuple[DesignSpec, Robot]:
    """The design of ``problem`` as values, and the robot it was resolved on (its pinocchio and coal
    objects, which :func:`~excite_cli.design.excitation.build_design` reuses in this process).

    Args:
        problem: the validated config.
        base: the robot's base parameters when already computed; default: computed here.

    Raises:
        ExciteError: bad robot, limits, effects or prior input (:func:`load_robot`,
            :func:`joint_limit_bounds`, :func:`design_effects`, :func:`measured_prior`).
    """
    robot = load_robot(problem.robot, problem.folder, needs_collision(problem))
    base = base or compute_base_parameters(robot)
    effects = design_effects(problem, robot, base)
    frame = scaled_frame(base, parameter_magnitudes(robot))
    if effects is not None:
        _, upper = joint_limit_bounds(problem.limits, robot)
        frame = block_diag(frame, np.diag(effects.magnitudes(robot.model.effortLimit[robot.v_idx], upper[1], upper[2])))
    return DesignSpec(problem, base, effects, frame, measured_prior(problem, robot)), robot
