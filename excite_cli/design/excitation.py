"""Everything one excitation design needs, built from its resolved values (:mod:`~excite_cli.design.spec`).

spec ─► robot, Fourier bases (cost samples, constraint grid, fine check grid), constraints ─► the
optimizer and the sequential generation use these, never the config file.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from excite_cli.collision.capsules import capsule_pairs, capsules_from_config
from excite_cli.collision.world import world_shapes
from excite_cli.config import ConstraintsConfig, LimitsConfig
from excite_cli.constraints import Constraint, JointLimits, SelfCollision, accepted
from excite_cli.constraints.com_region import com_region_from_config
from excite_cli.constraints.joint_limits import joint_limit_bounds
from excite_cli.constraints.lse import GRID_MARGIN
from excite_cli.constraints.torque_limits import TorqueLimits, TorqueUse, torque_limit, torque_use_fraction
from excite_cli.constraints.world_collision import WorldCollision
from excite_cli.constraints.zmp import zmp_from_config
from excite_cli.criteria import criterion_record
from excite_cli.design.criterion import Criterion, condition_number
from excite_cli.design.information import PriorInformation, excitation_level, parameter_magnitudes
from excite_cli.design.noise import RowNoise, row_noise
from excite_cli.design.spec import DesignSpec, needs_collision
from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.effect_columns import EffectColumns
from excite_cli.dynamics.robot import Robot, load_robot
from excite_cli.errors import ExciteError
from excite_cli.stored.design_model import MeasuredPrior
from excite_cli.trajectory.boundary import BoundaryConditions, boundary_conditions
from excite_cli.trajectory.fourier import FourierBasis, FourierTrajectory, sample_times

#: Decimals [rad] random starts are rounded to (see :meth:`Excitation.random_start`).
START_DECIMALS = 9


@dataclass
class Excitation:
    """A ready-to-optimize excitation problem.

    Attributes:
        spec: the values it was built from (:class:`~excite_cli.design.spec.DesignSpec`): the config's
            sections, the base parameters, the effect columns, the scaling frame, the measured prior's
            weights.
        robot: the robot (this process's pinocchio and coal objects).
        trajectory: the Fourier parameterization (Eq. 50).
        cost_basis: basis at the T cost samples (regressor rows, Eq. 3).
        grid_basis: basis on the constraint grid (every ``constraint_period``, end included).
        fine_basis: basis on the check grid, ``check_refinement`` times finer.
        limits: joint limits (Eq. 51).
        constraints: all constraints handed to the optimizer (joint limits first).
        boundary: boundary conditions (rest or periodic) and the optimizer's coordinates.
    """

    spec: DesignSpec
    robot: Robot
    trajectory: FourierTrajectory
    cost_basis: FourierBasis
    grid_basis: FourierBasis
    fine_basis: FourierBasis
    limits: JointLimits
    constraints: list[Constraint]
    boundary: BoundaryConditions

    @property
    def base(self) -> BaseParameters:
        """The robot's base parameters (Eq. 2)."""
        return self.spec.base

    @property
    def effects(self) -> EffectColumns | None:
        """The effect columns designed for beside the base columns (``effects``), or None."""
        return self.spec.effects

    @property
    def scaled_frame(self) -> np.ndarray:
        """L (b+e, b+e), read-only (:attr:`~excite_cli.design.spec.DesignSpec.scaled_frame`)."""
        return self.spec.scaled_frame

    @property
    def measured(self) -> MeasuredPrior | None:
        """How the rows of ``sequence.prior`` weigh when it is an identify report, or None."""
        return self.spec.measured

    def criterion(
        self,
        prior: np.ndarray | PriorInformation | None = None,
        objective: str | None = None,
        scaling: str | None = None,
        weighed: bool = True,
    ) -> Criterion:
        """The criterion of ``objective`` (default ``optimizer.objective``) with C₀ = ``prior`` (m₁, b+e)
        (Eq. 41), the rows or their information (a restart is sent the b+e-square blocks, not the
        rows), of C (``scaling`` ``none``) or of C L (``urdf``; default ``optimizer.scaling``, else
        the criterion's own, :attr:`~excite_cli.criteria.record.CriterionRecord.scaling`); its rows
        weighed by their noise (:attr:`noise`), or with ``weighed`` False every row as it is (the
        paper's C, which Table I reports)."""
        objective = objective or self.spec.optimizer.objective
        scaling = scaling or self.spec.optimizer.scaling_of(objective)
        return Criterion(
            self.robot,
            self.base,
            self.cost_basis,
            prior=PriorInformation.of(prior) if isinstance(prior, np.ndarray) else prior,
            objective=criterion_record(objective),
            frame=self.scaled_frame if scaling == "urdf" else None,
            effects=self.effects,
            noise=self.noise if weighed else None,
        )

    def excitation_level(self, C: np.ndarray) -> float:
        """ē(C) [N·m] of base-regressor rows C (M, b+e), the excitation figure that does not depend on
        the choice of base columns (:mod:`excite_cli.design.information`)."""
        b = self.base.count
        return excitation_level(C, self.base, parameter_magnitudes(self.robot), np.diag(self.scaled_frame)[b:])

    def scaled_condition_number(self, C: np.ndarray) -> float:
        """cond(C L) of base-regressor rows C (M, b+e): the condition number that does not depend on
        the choice of base columns (:mod:`excite_cli.design.information`)."""
        return condition_number(C @ self.scaled_frame)

    @property
    def columns(self) -> int:
        """b + e: the regressor's columns, base parameters then effect columns."""
        return self.spec.columns

    @cached_property
    def noise(self) -> RowNoise | None:
        """The regressor rows' noise (``noise``, σ_j from a measured prior's report), or None: unweighted;
        resolved once per design (every criterion it builds takes the same)."""
        return row_noise(self.spec.noise, self.robot, self.measured, self.spec.hedged)

    @property
    def effect_names(self) -> tuple[str, ...]:
        """(e,) the effect columns' coefficient names (none without effects)."""
        return self.effects.names if self.effects else ()

    @property
    def home(self) -> np.ndarray:
        """(n,) the robot's home posture [rad] moved inside the position bounds by their margin."""
        return home_posture(self.robot, self.limits)

    def static(self) -> np.ndarray:
        """α (n, 2N+1) of standing still at the home posture."""
        alpha = np.zeros((self.robot.n_joints, self.trajectory.n_coefficients))
        alpha[:, 0] = self.home
        return alpha

    def random_motion(self, rng: np.random.Generator, fill: float) -> np.ndarray:
        """Random α (n, 2N+1) about the home posture that meets the boundary conditions and fills the
        fraction ``fill`` of each joint's position, velocity and acceleration room on the grid."""
        return self.limits.random_start(self.trajectory.n_coefficients, rng, fill, self.home, self.boundary.wave_space)

    def random_start(self, rng: np.random.Generator) -> np.ndarray:
        """Random α (n, 2N+1) about the home posture that every constraint (but those that need
        motion) and the boundary conditions accept: random Fourier coefficients filling 50-90 % of
        the joint limits, shrunk until the other constraints hold.

        The drawn oscillation coefficients are rounded to ``START_DECIMALS`` decimals [rad] and moved
        back into the oscillations that meet the boundary conditions (by loops that do not depend on
        BLAS threads), so that the rounding of the matrix products that scaled them, which depends on
        the BLAS library, its threads and the processor, does not reach the start: one seed gives the
        same start with any thread setting, unless a coefficient falls within rounding of a decimal's
        edge (a chance of about 10⁻⁴ per start on the G1 problem's 294 coefficients)."""
        alpha = self.random_motion(rng, rng.uniform(0.5, 0.9))
        waves = self.boundary.wave_space
        alpha[:, 1:] = np.einsum("jm,mr,kr->jk", np.round(alpha[:, 1:], START_DECIMALS), waves, waves, optimize=False)
        for _ in range(40):
            if accepted([c for c in self.constraints if not c.needs_motion], alpha):
                return alpha
            alpha[:, 1:] *= 0.7
        return self.static()


def home_posture(robot: Robot, limits: JointLimits) -> np.ndarray:
    """(n,) the robot's home posture [rad] moved inside the position bounds by their margin."""
    inner = (1.0 - GRID_MARGIN) * limits.half[0]
    return np.clip(robot.home, limits.centre[0] - inner, limits.centre[0] + inner)


def build_design(spec: DesignSpec, robot: Robot | None = None, check_home: bool = True) -> Excitation:
    """Set up bases and constraints for ``spec``: what the main process and every worker build.

    Args:
        spec: the resolved design.
        robot: the robot it was resolved on, in this process; default: loaded here (a worker's own
            pinocchio and coal objects).
        check_home: refuse a home posture that violates a constraint (off: a caller searching for one,
            or a worker building what the main process checked).

    Raises:
        ExciteError: fewer regressor rows than columns (``trajectory.cost_samples``), bad limits input
            (:func:`joint_limit_bounds`), a bad noise section, a constraint violated at the home
            posture (with ``check_home``).
    """
    robot = robot or load_robot(spec.robot, spec.folder, needs_collision(spec.constraints))
    tcfg = spec.trajectory
    if tcfg.cost_samples * robot.n_rows < spec.columns:
        effect_part = f" and {spec.effects.count} effect columns" if spec.effects else ""
        raise ExciteError(
            "trajectory.cost_samples",
            f"{tcfg.cost_samples} samples × {robot.n_rows} regressor rows are fewer "
            f"than the robot's {spec.base.count} base parameters{effect_part}; cond(C) would be infinite",
        )
    trajectory = FourierTrajectory(tcfg.harmonics, tcfg.base_frequency)
    fine_period = tcfg.constraint_period / spec.limits.check_refinement
    grid_basis = trajectory.basis(sample_times(tcfg.duration, tcfg.constraint_period, include_end=True))
    limits = JointLimits(*joint_limit_bounds(spec.limits, robot), grid_basis, robot.joint_names)
    excitation = Excitation(
        spec=spec,
        robot=robot,
        trajectory=trajectory,
        cost_basis=trajectory.basis(sample_times(tcfg.duration, tcfg.cost_period)),
        grid_basis=grid_basis,
        fine_basis=trajectory.basis(sample_times(tcfg.duration, fine_period, include_end=True)),
        limits=limits,
        constraints=_constraints(spec.limits, spec.constraints, robot, grid_basis, limits),
        boundary=boundary_conditions(tcfg, trajectory, limits.coefficient_scale(), home_posture(robot, limits)),
    )
    excitation.noise  # the noise section resolved and checked before any work
    if check_home:
        _check_home_posture(excitation)
    return excitation


def _constraints(
    lcfg: LimitsConfig, ccfg: ConstraintsConfig, robot: Robot, grid_basis: FourierBasis, limits: JointLimits
) -> list[Constraint]:
    """Every constraint of the sections ``limits`` and ``constraints`` on the constraint grid, the joint
    limits first."""
    constraints: list[Constraint] = [limits]
    if lcfg.torque is not None:
        constraints.append(TorqueLimits(robot, grid_basis, torque_limit(lcfg.torque, robot)))
    if lcfg.min_torque_use is not None:
        fraction = torque_use_fraction(lcfg.min_torque_use, robot)
        limit = torque_limit(lcfg.torque or "urdf", robot)
        constraints.append(TorqueUse(robot, grid_basis, limit, fraction))
    if ccfg.com is not None:
        constraints.append(com_region_from_config(ccfg.com, robot, grid_basis))
    if ccfg.zmp is not None:
        constraints.append(zmp_from_config(ccfg.zmp, robot, grid_basis))
    if ccfg.self_collision is not None:
        capsules = capsules_from_config(ccfg.self_collision, robot)
        pairs = capsule_pairs(ccfg.self_collision, robot, capsules)
        constraints.append(SelfCollision(robot, grid_basis, capsules, pairs, ccfg.self_collision.margin))
    if ccfg.environment is not None:
        capsules = capsules_from_config(ccfg.environment, robot, "constraints.environment")
        world = WorldCollision(robot, grid_basis, capsules, world_shapes(ccfg.environment))
        if world.pairs:  # else no moving capsule can come within a shape's margin
            constraints.append(world)
    return constraints


def violated_at_rest(excitation: Excitation, posture: np.ndarray | None = None) -> tuple[str, str] | None:
    """The first constraint (its field and where) that standing still at ``posture`` (n,) [rad]
    (default: the home posture) violates, or None."""
    static = excitation.static()
    if posture is not None:
        static[:, 0] = posture
    for c in (c for c in excitation.constraints if not c.needs_motion):
        check = c.check(static, excitation.grid_basis)
        if check.max_violation > -c.grid_margin:
            return c.field, check.where or "joint limits"
    return None


def _check_home_posture(excitation: Excitation) -> None:
    """Stop before optimizing when standing still at the home posture already violates a constraint.

    Raises:
        ExciteError: naming the constraint and where it fails (the capsule pair, the CoM distance).
    """
    violated = violated_at_rest(excitation)
    if violated is not None:
        raise ExciteError(
            violated[0], f"violated before optimization, at the home posture with the locked joints: {violated[1]}"
        )
