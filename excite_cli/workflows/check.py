"""``check``: what an ``optimize`` config will do, without optimizing: the problem is built exactly as
``optimize`` builds it (so it refuses what the run would refuse), then summarized with a run time
estimated from timed evaluations of the criterion and the constraints."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from excite_cli.config import Problem
from excite_cli.optimization.engine import default_workers
from excite_cli.optimization.excitation import Excitation, build_excitation

#: Evaluations timed for the estimate (the median is kept).
TIMED = 5
#: Solver work per iteration beyond the criterion and constraints (line search, QP): a factor
#: measured on the shipped configs (the estimate against the run's wall time).
SOLVER_OVERHEAD = 1.5


@dataclass
class ConstraintSize:
    """One constraint handed to the optimizer: its name, its rows (values per evaluation) and what
    they are, in words."""

    name: str
    rows: int
    what: str


@dataclass
class Plan:
    """What ``optimize`` would run.

    Attributes:
        excitation: the problem as ``optimize`` builds it.
        constraints: one :class:`ConstraintSize` per constraint.
        excluded_pairs: capsule pairs (link, link) excluded by the config.
        variables: Fourier coefficients the optimizer moves (n × (2N + 1)).
        seconds_per_iteration: one solver iteration [s] (criterion and gradient, every constraint
            and its Jacobian, times :data:`SOLVER_OVERHEAD`).
        iterations: solver iterations of one sequential iteration at most (starts and restarts).
        workers: processes the restarts share.
        estimate: the whole run at most [s] (every restart to ``max_iterations``).
    """

    excitation: Excitation
    constraints: list[ConstraintSize]
    excluded_pairs: list[tuple[str, str]]
    variables: int
    seconds_per_iteration: float
    iterations: int
    workers: int
    estimate: float


def _what(constraint, joints: int) -> str:
    """The rows of a constraint in words."""
    pairs = getattr(constraint, "pairs", [])
    if constraint.name == "self_collision":
        links = {frozenset((constraint.capsules[i].link, constraint.capsules[j].link)) for i, j in pairs}
        return f"one per capsule pair ({len(pairs)}, of {len(links)} link pairs)"
    if constraint.name == "world_collision":
        return f"one per capsule and world shape ({len(pairs)})"
    if constraint.name == "joint_limits":
        return f"position, velocity, acceleration × lower, upper × {joints} joints"
    return constraint.field


def plan_optimize(problem: Problem) -> Plan:
    """Build ``problem`` as ``optimize`` does and time one solver iteration.

    Raises:
        ExciteError: what ``optimize`` would refuse before optimizing (see :func:`build_excitation`):
            a bad robot, limits that leave no motion, a constraint violated at the home posture.
    """
    excitation = build_excitation(problem)
    alpha = excitation.random_start(np.random.default_rng(problem.optimizer.seed))
    criterion = excitation.criterion()
    n = excitation.robot.n_joints
    sizes = [ConstraintSize(c.name, int(np.size(c.values(alpha))), _what(c, n)) for c in excitation.constraints]
    timings = []
    for _ in range(TIMED):
        start = time.perf_counter()
        criterion.value_and_gradient(alpha)
        for c in excitation.constraints:
            c.evaluate(alpha)
        timings.append(time.perf_counter() - start)
    cfg = problem.optimizer
    workers = 1 if cfg.workers == 1 else min(cfg.workers or default_workers(), max(cfg.restarts, cfg.screened))
    per_iteration = SOLVER_OVERHEAD * float(np.median(timings))
    self_collision = problem.constraints.self_collision
    excluded = [tuple(p) for p in self_collision.exclude_pairs] if self_collision else []
    return Plan(
        excitation=excitation,
        constraints=sizes,
        excluded_pairs=excluded,
        variables=int(alpha.size),
        seconds_per_iteration=per_iteration,
        iterations=cfg.planned_iterations,
        workers=workers,
        estimate=per_iteration * cfg.planned_iterations * problem.sequence.iterations / workers,
    )
