"""The config resolved into a design (:class:`~excite_cli.design.spec.DesignSpec`), and the excitation
built from it: the design's one reader of the whole config.

    config ─► resolve(problem) ─► DesignSpec ─► build_design(spec) ─► Excitation
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.linalg import block_diag

from excite_cli.config import Problem, effective_yaml
from excite_cli.constraints.joint_limits import joint_limit_bounds
from excite_cli.criteria.catalogue import criterion_record
from excite_cli.design.excitation import Excitation, build_design
from excite_cli.design.information import parameter_magnitudes, scaled_frame
from excite_cli.design.model_columns import design_effects, measured_prior
from excite_cli.design.noise import hedged_noise, typical_torques
from excite_cli.design.spec import ConfigText, DesignSpec, needs_collision
from excite_cli.dynamics.base_parameters import BaseParameters, compute_base_parameters
from excite_cli.dynamics.robot import Robot, load_robot
from excite_cli.stored.inputs import StoredInputs, read_inputs


def resolve(
    problem: Problem, base: BaseParameters | None = None, stored: StoredInputs | None = None
) -> tuple[DesignSpec, Robot]:
    """The design of ``problem`` as values, and the robot it was resolved on (its pinocchio and coal
    objects, which :func:`~excite_cli.design.excitation.build_design` reuses in this process); with
    nothing declared of the noise, the hedge for it (:func:`_hedged`).

    Args:
        problem: the validated config.
        base: the robot's base parameters when already computed; default: computed here.
        stored: the files of ``effects.model`` and ``sequence.prior``, read once by the caller that
            uses them again; default: read here (:func:`~excite_cli.stored.inputs.read_inputs`).

    Raises:
        ExciteError: bad robot, limits, effects or prior input (:func:`load_robot`,
            :func:`joint_limit_bounds`, :func:`design_effects`, :func:`measured_prior`).
    """
    p = problem
    robot = load_robot(p.robot, p.folder, needs_collision(p.constraints))
    base = base or compute_base_parameters(robot)
    stored = stored or read_inputs(p.effects.model, p.sequence.prior, p.folder)
    effects = design_effects(p.effects, stored, robot, base)
    frame = scaled_frame(base, parameter_magnitudes(robot))
    if effects is not None:
        _, upper = joint_limit_bounds(p.limits, robot)
        frame = block_diag(frame, np.diag(effects.magnitudes(robot.model.effortLimit[robot.v_idx], upper[1], upper[2])))
    text = ConfigText(effective_yaml(p), p.source_text, str(p.source_path or ""))
    sections = (p.robot, p.trajectory, p.limits, p.constraints, p.optimizer, p.sequence, p.noise, p.folder, text)
    spec = DesignSpec(*sections, base, effects, frame, measured_prior(stored.prior, robot))
    return _hedged(spec, robot), robot


def _hedged(spec: DesignSpec, robot: Robot) -> DesignSpec:
    """``spec`` with the hedge for undeclared noise (:func:`~excite_cli.design.noise.hedged_noise` on the
    joints' typical torques, :func:`~excite_cli.design.noise.typical_torques`) where it declares no
    ``noise``, has no measured prior and optimizes a criterion of the estimate's covariance
    (``CriterionRecord.hedged``: not the paper's condition number, which is of the rows as they are),
    and the robot has torques (a file without inertias has none for the noise to grow with); else
    ``spec``."""
    if spec.noise is not None or spec.measured is not None:
        return spec
    if not criterion_record(spec.optimizer.objective).hedged:
        return spec
    typical = typical_torques(build_design(spec, robot, check_home=False))
    if not typical.max() > 0.0:
        return spec
    return replace(spec, noise=hedged_noise(robot.joint_names, typical), hedged=True)


def build_excitation(
    problem: Problem,
    base: BaseParameters | None = None,
    check_home: bool = True,
    stored: StoredInputs | None = None,
) -> Excitation:
    """Resolve ``problem`` (:func:`resolve`) and build its excitation
    (:func:`~excite_cli.design.excitation.build_design`).

    Args:
        problem: the validated config.
        base: the robot's base parameters when already computed; default: computed here.
        check_home: refuse a home posture that violates a constraint (off: a caller searching for one).
        stored: see :func:`resolve`.

    Raises:
        ExciteError: see :func:`resolve` and :func:`~excite_cli.design.excitation.build_design`.
    """
    spec, robot = resolve(problem, base, stored)
    return build_design(spec, robot, check_home)
