"""The optimization problem as a solver sees it: the criterion and the stacked constraints in the
optimizer's variables z (:mod:`excite_cli.trajectory.boundary`), each evaluated once per point; the
epigraph form of a criterion of the extreme singular values; and the feasible point nearest to a
solver's iterate (or, where that fails, a feasible point towards it)."""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np
from scipy.optimize import minimize

from excite_cli.constraints import Constraint, accepted, farthest_accepted
from excite_cli.design.criterion import Criterion
from excite_cli.memo import once
from excite_cli.search.kkt import (
    CLUSTER_SIZE,
    End,
    Optimality,
    clarke_optimality,
    extreme_clusters,
    kkt_optimality,
)
from excite_cli.trajectory.boundary import BoundaryConditions
from excite_cli.trajectory.fourier import FourierBasis

#: Bisection steps towards a feasible point (the segment's length / 2¹²).
BISECTIONS = 12
#: SLSQP iterations of the projection onto the feasible set (it converges in 10-50 on the G1 problem).
PROJECTION_ITERATIONS = 60
#: Singular values at each extreme the epigraph form bounds (one solver constraint each).
EPIGRAPH_SIZE = CLUSTER_SIZE
#: A bound's gradient is computed (a pass of RNEA derivatives) where its log σ is within this [1] of
#: its extreme, and for the next singular value beyond them on each side whatever its distance (the
#: first a step raising the cluster would bring into it); a farther one's row of the Jacobian is zero.
EPIGRAPH_BAND = 0.05
#: Projections with a larger margin (2, 4, 8 × the overshoot) before a point the fine check rejects
#: is moved towards the start (:func:`onto_fine_grid`).
FINE_PROJECTIONS = 3


class Evaluations:
    """The solver's callbacks in its variables z: the objective, its gradient, the stacked constraint
    values and their Jacobian, each computed once per point and only when asked for (a line search's
    trial points need values only); remembers the best point whose aggregated constraints all hold.

    Attributes:
        best_value: the lowest objective at such a point (``start_value`` until one is seen).
        best_inside: its α (n, 2N+1), or None.
        margins: per constraint, the room [1, normalized] its aggregated values keep beyond the
            aggregation's own (:func:`onto_fine_grid`; 0 unless a fine check asked for more).
    """

    def __init__(
        self,
        criterion: Criterion,
        constraints: Sequence[Constraint],
        boundary: BoundaryConditions,
        start_value: float,
        margins: Sequence[float] = (),
    ):
        self.criterion, self.all, self.boundary = criterion, constraints, boundary
        self.best_value, self.best_inside = start_value, None
        self.margins = tuple(float(m) for m in margins) if len(margins) else (0.0,) * len(constraints)

    def tightened(self, extra: Sequence[float]) -> "Evaluations":
        """The same problem with each constraint's margin raised by ``extra`` (one per constraint) [1]."""
        return Evaluations(
            self.criterion, self.all, self.boundary, self.best_value, np.add(self.margins, extra).tolist()
        )

    def value(self, z: np.ndarray) -> float:
        """The criterion at z."""

        def compute() -> float:
            alpha = self.boundary.to_alpha(z)
            value = self.criterion.value(alpha, from_gram=True)
            if (
                value < (self.best_value if self.best_inside is not None else np.inf)
                and self.constraint_values(z).max() <= 0.0
            ):
                self.best_value, self.best_inside = value, alpha.copy()
            return value

        return once(self, "value", z, compute)

    def gradient(self, z: np.ndarray) -> np.ndarray:
        """The criterion's gradient in z (n_z,)."""
        return once(
            self,
            "gradient",
            z,
            lambda: self.boundary.chain(self.criterion.value_and_gradient(self.boundary.to_alpha(z))[1].ravel()),
        )

    def constraint_values(self, z: np.ndarray) -> np.ndarray:
        """Stacked constraint values g (m,), each with its constraint's margin."""
        alpha = self.boundary.to_alpha(z)
        return once(
            self, "values", z, lambda: np.concatenate([c.values(alpha) + m for c, m in zip(self.all, self.margins)])
        )

    def constraint_jacobian(self, z: np.ndarray) -> np.ndarray:
        """Their Jacobian in z (m, n_z)."""
        alpha = self.boundary.to_alpha(z)
        return once(self, "jacobian", z, lambda: self.boundary.chain(np.vstack([c.jacobian(alpha) for c in self.all])))

    def objective(self, z: np.ndarray) -> tuple[float, np.ndarray]:
        """The criterion and its gradient in z."""
        return self.value(z), self.gradient(z)

    def constraints(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Stacked values g (m,) and Jacobian in z."""
        return self.constraint_values(z), self.constraint_jacobian(z)

    def optimality(self, alpha: np.ndarray) -> Optimality:
        """First-order optimality at α (n, 2N+1), in the variables z."""
        return self.kkt(self.boundary.to_variables(alpha))

    def kkt(self, z: np.ndarray, nonsmooth: bool = True) -> Optimality:
        """First-order optimality at z (n_z,): the KKT residual, or (``nonsmooth``) for a criterion of
        the extreme singular values where one is multiple, Clarke's
        (:mod:`~excite_cli.search.kkt`), whichever is smaller."""
        smooth = kkt_optimality(self.gradient(z), *self.constraints(z))
        if not nonsmooth or not self.criterion.objective.extremes or smooth.residual == 0.0:
            return smooth
        return once(self, "clarke", z, lambda: self._clarke(z, smooth))

    def _clarke(self, z: np.ndarray, smooth: Optimality) -> Optimality:
        """The Clarke residual at z where an extreme singular value is multiple, else ``smooth``."""
        alpha, record = self.boundary.to_alpha(z), self.criterion.objective
        clusters = extreme_clusters(self.criterion.singular_values(alpha), record.extremes)
        if all(len(indices) == 1 for indices, _ in clusters):
            return smooth
        scale = self.criterion.value(alpha) if record.exponentiate_extremes else 1.0
        pieces = []
        for indices, weight in clusters:
            gradients = self.criterion.cluster_gradients(alpha, indices)
            k = len(indices)
            pieces.append(scale * weight * self.boundary.chain(gradients.reshape(k * k, -1)).reshape(k, k, -1))
        clarke = clarke_optimality(pieces, self.gradient(z), *self.constraints(z))
        return clarke if clarke.residual < smooth.residual else smooth


class Epigraph:
    """The epigraph form of a criterion of the extreme singular values (cond, log cond, E-optimality:
    :attr:`~excite_cli.criteria.record.CriterionRecord.extremes` = (w_max, w_min)), smooth where the
    criterion is not (shared/DESIGN.md, "Optimizing cond is non-smooth"), in the variables w = (z, t):

        minimize Σ_k w_k t_k  s.t.  g(z) ≤ 0,  log σ_i(z) ≤ t_max for the ``EPIGRAPH_SIZE`` largest σ_i,
                                               log σ_i(z) ≥ t_min for the ``EPIGRAPH_SIZE`` smallest

    (an extreme weighed zero has no t). At a solution t_max = log σ_max and t_min = log σ_min, the
    objective is w_max log σ_max + w_min log σ_min (log cond; cond is its exponential, with the same
    minimizers), and its KKT conditions are Clarke's for the criterion with the weights S of a multiple
    singular value's subdifferential diagonal in the current singular vectors: the bounds' multipliers
    weigh the singular values' own gradients, not their cross terms (Overton 1992). The solver sees
    this problem; everything else z (its end is judged by Clarke's full test, kkt.clarke_optimality).
    """

    def __init__(self, problem: Evaluations):
        self.problem = problem
        self.sides = problem.criterion.objective.weighed_extremes

    def start(self, z: np.ndarray) -> np.ndarray:
        """w (n_z + sides,) at z (n_z,): each t at its extreme log σ."""
        logs = np.log(self._singular_values(z))
        return np.concatenate([z, [logs[-1] if side == 0 else logs[0] for side, _ in self.sides]])

    def _singular_values(self, z: np.ndarray) -> np.ndarray:
        return self.problem.criterion.floored_singular_values(self.problem.boundary.to_alpha(z))

    def value(self, w: np.ndarray) -> float:
        return float(sum(weight * t for (_, weight), t in zip(self.sides, w[-len(self.sides) :])))

    def gradient(self, w: np.ndarray) -> np.ndarray:
        return np.concatenate([np.zeros(w.size - len(self.sides)), [weight for _, weight in self.sides]])

    def _bounds(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The bounded singular values' log σ_i (m_e,), their gradients in z (m_e, n_z), each bound's
        side (m_e,) and sign (+1: log σ_i ≤ t, −1: log σ_i ≥ t)."""

        def compute():
            logs = np.log(self._singular_values(z))
            count = min(EPIGRAPH_SIZE, logs.size)
            indices, sides, signs = [], [], []
            for k, (side, _) in enumerate(self.sides):
                indices.append(np.arange(logs.size - 1, logs.size - 1 - count, -1) if side == 0 else np.arange(count))
                sides.append(np.full(count, k))
                signs.append(np.full(count, 1.0 if side == 0 else -1.0))
            indices, sides, signs = np.concatenate(indices), np.concatenate(sides), np.concatenate(signs)
            extreme = np.where(signs > 0, logs[-1], logs[0])
            inside = (np.abs(logs[indices] - extreme) <= EPIGRAPH_BAND).reshape(len(self.sides), count)
            reach = np.minimum(inside.sum(axis=1) + 1, count)  # the cluster (a prefix) and the next one
            near = np.unique(indices[(np.arange(count) < reach[:, None]).ravel()])
            gradients = np.zeros((indices.size, z.size))
            if near.size:
                _, alpha_gradients = self.problem.criterion.log_singular_values(self.problem.boundary.to_alpha(z), near)
                chained = self.problem.boundary.chain(alpha_gradients.reshape(near.size, -1))
                for row, i in enumerate(near):
                    gradients[indices == i] = chained[row]
            return logs[indices], gradients, sides, signs

        return once(self.problem, "epigraph", z, compute)

    def constraint_values(self, w: np.ndarray) -> np.ndarray:
        z, t = w[: -len(self.sides)], w[-len(self.sides) :]
        logs, _, sides, signs = self._bounds(z)
        return np.concatenate([self.problem.constraint_values(z), signs * (logs - t[sides])])

    def constraint_jacobian(self, w: np.ndarray) -> np.ndarray:
        z = w[: -len(self.sides)]
        _, gradients, sides, signs = self._bounds(z)
        jacobian = self.problem.constraint_jacobian(z)
        bounds_t = np.zeros((sides.size, len(self.sides)))
        bounds_t[np.arange(sides.size), sides] = -signs
        top = np.hstack([jacobian, np.zeros((jacobian.shape[0], len(self.sides)))])
        return np.vstack([top, np.hstack([signs[:, None] * gradients, bounds_t])])


def project(problem: Evaluations, z: np.ndarray, iterations: int = PROJECTION_ITERATIONS) -> Optional[np.ndarray]:
    """The feasible point nearest to z (n_z,) in the optimizer's (preconditioned) variables:
    argmin ½‖y − z‖² s.t. g(y) ≤ 0, by SLSQP from z (a convex objective: it converges where the
    criterion's problem does not), then the constraints' own exact repairs. Returns its α (n, 2N+1)
    if every constraint accepts it, else None."""
    result = minimize(
        lambda y: (0.5 * float((y - z) @ (y - z)), y - z),
        z,
        jac=True,
        method="SLSQP",
        constraints=[
            {
                "type": "ineq",
                "fun": lambda y: -problem.constraint_values(y),
                "jac": lambda y: -problem.constraint_jacobian(y),
            }
        ],
        options={"maxiter": iterations, "ftol": 1e-12},
    )
    alpha = problem.boundary.to_alpha(result.x)
    for c in problem.all:
        alpha = c.restore(alpha)
    alpha = problem.boundary.project(alpha)
    return alpha if accepted(problem.all, alpha) else None


def onto_fine_grid(
    problem: Evaluations, alpha: np.ndarray, start: np.ndarray, fine_basis: FourierBasis
) -> tuple[Evaluations, np.ndarray, str]:
    """α (n, 2N+1), which the constraints accept on their grid, moved until they accept it on the
    instants of ``fine_basis`` too: the problem it then belongs to, the point and how it was found,
    ``projected`` or ``bisection``.

    Between grid instants a sample can overshoot by more than the aggregation's margin covers (the
    G1, seed 0, iteration 3: two capsules 0.15 mm inside their 1 cm margin at a restart's end).
    Moved towards ``start`` (n, 2N+1; every constraint accepts it) until the check held, that
    restart kept 36 % of its motion (criterion 3.007 where it had reached 2.826). Instead each
    constraint the check rejects gets a margin of its own, twice its normalized violation (then 4
    and 8 times), and α is projected onto that problem (:func:`project`), which the restart's
    optimality and any continuation of it then belong to; only if none of these holds is α moved
    towards ``start`` (``bisection``: never kept)."""
    violations = np.array([max(c.check(alpha, fine_basis).max_violation, 0.0) for c in problem.all])
    for k in range(1, FINE_PROJECTIONS + 1):
        tightened = problem.tightened(violations * 2.0**k)
        projected = project(tightened, problem.boundary.to_variables(alpha))
        if projected is not None and accepted(problem.all, projected, fine_basis):
            return tightened, projected, End.PROJECTED
    t = farthest_accepted(problem.all, start, alpha, BISECTIONS, fine_basis)
    return problem, start + t * (alpha - start), End.BISECTION


def repair(
    constraints: Sequence[Constraint],
    alpha: np.ndarray,
    feasible: np.ndarray,
    boundary: Optional[BoundaryConditions] = None,
    steps: int = BISECTIONS,
) -> np.ndarray:
    """A feasible point near α: the constraints' own exact repairs, moved back onto the boundary
    conditions, then, if some constraint still rejects it, the farthest point towards it from
    ``feasible`` (bisection on the segment, which keeps the boundary conditions: they are affine).

    Args:
        constraints: all constraints.
        alpha: (n, 2N+1) point to repair, typically the last SQP iterate.
        feasible: (n, 2N+1) point every constraint accepts (the restart's start).
        boundary: the boundary conditions both points meet, if any.
        steps: bisection steps.
    """
    for c in constraints:
        alpha = c.restore(alpha)
    if boundary is not None:
        alpha = boundary.project(alpha)
    if accepted(constraints, alpha):
        return alpha
    return feasible + farthest_accepted(constraints, feasible, alpha, steps) * (alpha - feasible)
