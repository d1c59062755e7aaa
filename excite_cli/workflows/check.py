"""``check``: what an ``optimize`` config will do, without optimizing: the problem is built exactly as
``optimize`` builds it (so it refuses what the run would refuse), then summarized with a run time
estimated from real solver iterations of it, timed (:mod:`~excite_cli.search.run_time`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from excite_cli.collision.world import world_shapes
from excite_cli.config import Problem
from excite_cli.design.excitation import Excitation
from excite_cli.design.resolve import build_excitation
from excite_cli.search.engine import default_workers
from excite_cli.search.kkt import ACTIVE_TOLERANCE
from excite_cli.search.run_time import Timing, measure, sequence_seconds
from excite_cli.search.solvers import criterion_scale


@dataclass
class ConstraintSize:
    """One constraint handed to the optimizer: its name, its rows (values per evaluation), what they
    are, in words, and the smallest and largest norm of its Jacobian rows in the optimizer's variables
    at the first random start (normalized units per unit variable: 1 moves a joint by a half-range)."""

    name: str
    rows: int
    what: str
    smallest_row: float = np.nan
    largest_row: float = np.nan


@dataclass
class Scaling:
    """How the problem looks to the solver at the first random start, in the optimizer's variables z
    (:mod:`excite_cli.trajectory.boundary`).

    Attributes:
        gradient: the criterion's largest gradient component ‖∇f‖_∞.
        scale: the factor the solver multiplies the criterion by
            (:func:`~excite_cli.search.solvers.criterion_scale`).
        active: constraints within ``ACTIVE_TOLERANCE`` of their bound.
        active_condition: condition number of those constraints' Jacobian (NaN when none is active;
            large: nearly parallel rows, which the solver's subproblems cannot tell apart).
    """

    gradient: float
    scale: float
    active: int
    active_condition: float


@dataclass
class Plan:
    """What ``optimize`` would run.

    Attributes:
        excitation: the problem as ``optimize`` builds it.
        constraints: one :class:`ConstraintSize` per constraint.
        excluded_pairs: capsule pairs (link, link) excluded by the config.
        unreached: environment shapes no moving capsule can come within the margin of, whatever the
            posture (:func:`~excite_cli.constraints.world_collision.distance_bound`): they add no rows.
        scaling: the criterion's and the constraints' scale at the first random start.
        variables: Fourier coefficients the optimizer moves (n × (2N + 1)).
        timing: one solver iteration, one run's own time and one evaluation of each piece, measured [s].
        iterations: solver iterations of one sequential iteration at most (starts and restarts).
        workers: processes the restarts share.
        estimate: the whole run [s], expected (:func:`~excite_cli.search.run_time.sequence_seconds`).
        at_most: the whole run [s] with every restart to its limit and every polish round.
    """

    excitation: Excitation
    constraints: list[ConstraintSize]
    excluded_pairs: list[tuple[str, str]]
    scaling: Scaling
    variables: int
    timing: Timing
    iterations: int
    workers: int
    estimate: float
    at_most: float
    unreached: list[str] = field(default_factory=list)


def plan_optimize(problem: Problem, timing: Timing | None = None, base=None) -> Plan:
    """Build ``problem`` as ``optimize`` does and time its solver iterations
    (:func:`~excite_cli.search.run_time.measure`), unless ``timing`` gives them (the same problem's, sized
    otherwise); ``base``: its base parameters, when known.

    Raises:
        ExciteError: what ``optimize`` would refuse before optimizing (see :func:`build_excitation`):
            a bad robot, limits that leave no motion, a constraint violated at the home posture.
    """
    excitation = build_excitation(problem, base)
    alpha = excitation.random_start(np.random.default_rng(problem.optimizer.seed))
    criterion = excitation.criterion()
    chain = excitation.boundary.chain
    sizes, values, rows = [], [], []
    for c in excitation.constraints:
        g, jacobian = c.evaluate(alpha)
        norms = np.linalg.norm(chain(jacobian), axis=1)
        sizes.append(ConstraintSize(c.name, g.size, c.in_words(), *(norms.min(), norms.max()) if g.size else ()))
        values.append(g)
        rows.append(chain(jacobian))
    values, rows = np.concatenate(values), np.vstack(rows)
    active = rows[values >= -ACTIVE_TOLERANCE]
    singular = np.linalg.svd(active, compute_uv=False) if active.size else np.zeros(0)
    gradient = chain(criterion.value_and_gradient(alpha)[1].ravel())
    scaling = Scaling(
        float(np.abs(gradient).max()),
        criterion_scale(gradient),
        active.shape[0],
        float(singular[0] / singular[-1])
        if singular.size and singular[-1] > 0
        else (np.inf if singular.size else np.nan),
    )
    timing = timing or measure(excitation, problem.optimizer, alpha)
    cfg = problem.optimizer
    workers = 1 if cfg.workers == 1 else min(cfg.workers or default_workers(), max(cfg.restarts, cfg.screened))
    self_collision = problem.constraints.self_collision
    excluded = [tuple(p) for p in self_collision.exclude_pairs] if self_collision else []
    reached = {name for c in excitation.constraints for name in c.shapes_in_reach()}
    shapes = world_shapes(problem.constraints.environment)
    return Plan(
        excitation=excitation,
        constraints=sizes,
        excluded_pairs=excluded,
        scaling=scaling,
        variables=int(alpha.size),
        timing=timing,
        iterations=cfg.planned_iterations,
        workers=workers,
        estimate=sequence_seconds(cfg, problem.sequence.iterations, workers, timing),
        at_most=sequence_seconds(cfg, problem.sequence.iterations, workers, timing, most=True),
        unreached=[s.name for s in shapes if s.name not in reached],
    )
