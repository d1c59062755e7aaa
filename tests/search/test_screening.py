"""SLSQP sees at most SCREEN_ROWS constraint rows: the rows that can bind take slots as the solver
moves, so the optimum is that of the whole problem (an analytic case: a projection onto a half-space
among 300)."""

import numpy as np

from excite_cli.search import screening
from excite_cli.search.solvers import solve


class _Projection:
    """min ½‖z − c‖² subject to aᵢᵀz − bᵢ ≤ 0 (300 rows): c = 10 e₁; row 0 is z₁ ≤ 5, the others point
    away from c (a₁ < 0) with bᵢ ∈ [1, 2], so the optimum is 5 e₁ exactly, row 0 alone binding, and at
    z = 0 row 0 is the lowest of all (−5 against −2…−1): outside the first slots."""

    def __init__(self, n: int = 10, rows: int = 300):
        rng = np.random.default_rng(0)
        A = rng.standard_normal((rows, n))
        A[:, 0] = -np.abs(A[:, 0]) - 0.1
        self.A = A / np.linalg.norm(A, axis=1, keepdims=True)
        self.b = rng.uniform(1.0, 2.0, rows)
        self.A[0], self.b[0] = np.eye(n)[0], 5.0
        self.c = 10.0 * np.eye(n)[0]

    def value(self, z):
        return 0.5 * float((z - self.c) @ (z - self.c))

    def gradient(self, z):
        return z - self.c

    def constraint_values(self, z):
        return self.A @ z - self.b

    def constraint_jacobian(self, z):
        return self.A


def test_the_first_slots_are_the_highest_rows_and_the_binding_row_enters():
    problem = _Projection()
    seen = screening.screened(problem, np.zeros(10))
    assert isinstance(seen, screening.Screened) and len(seen.slots) == screening.SCREEN_ROWS
    assert 0 not in seen.slots
    assert seen.constraint_values(4.5 * np.eye(10)[0]).size == screening.SCREEN_ROWS  # row 0 at −0.5 > −ENTER
    assert 0 in seen.slots


def test_slsqp_on_the_screened_rows_reaches_the_whole_problems_optimum():
    problem = _Projection()
    run = solve("SLSQP", problem, np.zeros(10), 100, 1e-12, lambda z: None, scale=1.0)
    np.testing.assert_allclose(run.z, 5.0 * np.eye(10)[0], atol=1e-8)
    assert problem.constraint_values(run.z).max() <= 1e-10


def test_a_problem_with_few_rows_is_handed_over_as_it_is():
    problem = _Projection(rows=100)
    assert screening.screened(problem, np.zeros(10)) is problem
