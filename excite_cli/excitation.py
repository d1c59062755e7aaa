"""Everything one excitation design needs, built once from a validated :class:`~excite_cli.config.Problem`.

config ─► robot, base parameters, Fourier bases (cost samples, constraint grid, fine check grid),
constraints ─► the optimizer and the sequential generation use these, never the config.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from excite_cli.base_parameters import BaseParameters, compute_base_parameters
from excite_cli.config import Problem
from excite_cli.constraints import Constraint, JointLimits
from excite_cli.constraints.joint_limits import joint_limit_bounds
from excite_cli.criterion import ConditionNumber
from excite_cli.robot import Robot, load_robot
from excite_cli.trajectory import FourierBasis, FourierTrajectory, sample_times


@dataclass
class Excitation:
    """A ready-to-optimize excitation problem.

    Attributes:
        problem: the validated config.
        robot, base: the robot and its base parameters (Eq. 2).
        trajectory: the Fourier parameterization (Eq. 50).
        cost_basis: basis at the T cost samples (regressor rows, Eq. 3).
        grid_basis: basis on the constraint grid (every ``constraint_period``, end included).
        fine_basis: basis on the check grid, ``check_refinement`` times finer.
        limits: joint limits (Eq. 51).
        constraints: all constraints handed to the optimizer.
    """

    problem: Problem
    robot: Robot
    base: BaseParameters
    trajectory: FourierTrajectory
    cost_basis: FourierBasis
    grid_basis: FourierBasis
    fine_basis: FourierBasis
    limits: JointLimits
    constraints: list[Constraint]

    def criterion(self, prior: np.ndarray | None = None) -> ConditionNumber:
        """The condition-number criterion with C₀ = ``prior`` (m₁, b) (Eq. 41)."""
        return ConditionNumber(
            self.robot,
            self.base,
            self.cost_basis,
            prior=np.zeros((0, self.base.count)) if prior is None else prior,
            log=self.problem.optimizer.objective == "log_cond",
        )


def build_excitation(problem: Problem) -> Excitation:
    """Load the robot and set up bases and constraints for ``problem``.

    Raises:
        ExciteError: bad robot or limits input (see :func:`load_robot`, :func:`joint_limit_bounds`).
    """
    robot = load_robot(problem)
    base = compute_base_parameters(robot)
    tcfg = problem.trajectory
    trajectory = FourierTrajectory(tcfg.harmonics, tcfg.base_frequency)
    fine_period = tcfg.constraint_period / problem.limits.check_refinement
    grid_basis = trajectory.basis(sample_times(tcfg.duration, tcfg.constraint_period, include_end=True))
    limits = JointLimits(*joint_limit_bounds(problem.limits, robot), grid_basis)
    return Excitation(
        problem=problem,
        robot=robot,
        base=base,
        trajectory=trajectory,
        cost_basis=trajectory.basis(sample_times(tcfg.duration, tcfg.cost_period)),
        grid_basis=grid_basis,
        fine_basis=trajectory.basis(sample_times(tcfg.duration, fine_period, include_end=True)),
        limits=limits,
        constraints=[limits],
    )
