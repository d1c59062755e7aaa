"""The feasible point nearest to a solver's iterate (or, where that fails, a feasible point towards
it), and a point the fine grid's check rejects moved onto it."""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np
from scipy.optimize import minimize

from excite_cli.constraints import Constraint, accepted, farthest_accepted
from excite_cli.search.kkt import End
from excite_cli.search.nlp import Evaluations
from excite_cli.trajectory.boundary import BoundaryConditions
from excite_cli.trajectory.fourier import FourierBasis

#: Bisection steps towards a feasible point (the segment's length / 2¹²).
BISECTIONS = 12
#: SLSQP iterations of the projection onto the feasible set (it converges in 10-50 on the G1 problem).
PROJECTION_ITERATIONS = 60
#: Projections with a larger margin (2, 4, 8 × the overshoot) before a point the fine check rejects
#: is moved towards the start (:func:`onto_fine_grid`).
FINE_PROJECTIONS = 3


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
