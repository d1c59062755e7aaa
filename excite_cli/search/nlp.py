"""The optimization problem as a solver sees it: the criterion and the stacked constraints in the
optimizer's variables z (:mod:`excite_cli.trajectory.boundary`), each evaluated once per point, and
the epigraph form of a criterion of the extreme singular values."""

from __future__ import annotations

from enum import Enum
from typing import Sequence

import numpy as np

from excite_cli.constraints import Constraint
from excite_cli.design.criterion import Criterion
from excite_cli.memo import once
from excite_cli.search.kkt import (
    CLUSTER_SIZE,
    Optimality,
    clarke_optimality,
    extreme_clusters,
    kkt_optimality,
)
from excite_cli.trajectory.boundary import BoundaryConditions

#: Singular values at each extreme the epigraph form bounds (one solver constraint each).
EPIGRAPH_SIZE = CLUSTER_SIZE
#: A bound's gradient is computed (a pass of RNEA derivatives) where its log σ is within this [1] of
#: its extreme, and for the next singular value beyond them on each side whatever its distance (the
#: first a step raising the cluster would bring into it); a farther one's row of the Jacobian is zero.
EPIGRAPH_BAND = 0.05


class NlpForm(Enum):
    """How the solver sees a restart's criterion (each problem class says which it is, ``form``)."""

    PLAIN = "the criterion itself"
    EPIGRAPH = "the epigraph form of its extreme singular values"
    SMOOTHED = "the smoothing of its extreme singular values"


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

    form = NlpForm.PLAIN

    @property
    def problem(self) -> "Evaluations":
        """The problem in z the solver's form is built on: this one."""
        return self

    def start(self, z: np.ndarray) -> np.ndarray:
        """The solver's variables at z (n_z,): z."""
        return z

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

    form = NlpForm.EPIGRAPH

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
