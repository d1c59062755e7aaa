"""``verify-gradient``: analytic gradients and constraint Jacobians against finite differences."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from excite_cli.config import MAX_SEED, Problem
from excite_cli.criteria import NAMES as OBJECTIVES
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import GradientCheck, check_gradient, constraint_jacobian_error
from excite_cli.errors import ExciteError
from excite_cli.search.sequence import stacked_regressors
from excite_cli.storage.results import read_iterations


@dataclass
class Verification:
    """``verify-gradient``: (point, objective, check) per row; (constraint, rows, error) per constraint."""

    gradients: list[tuple[str, str, GradientCheck]]
    jacobians: list[tuple[str, int, float]]

    @property
    def worst(self) -> float:
        """The largest relative error against central differences."""
        return max([c.error_central for _, _, c in self.gradients] + [e for _, _, e in self.jacobians])


def run_verify(
    problem: Problem,
    result: Optional[Path] = None,
    objectives: Sequence[str] = OBJECTIVES,
    step: float = 1e-6,
    seed: int = 0,
    tolerance: float = 1e-6,
) -> Verification:
    """Every criterion's analytic gradient against finite differences at a random feasible α (and at
    the last optimum of ``result``, with the earlier iterations as C₀), and every constraint's
    Jacobian against central differences at a livelier α.

    Raises:
        ExciteError: an unknown objective, a bad step or tolerance (the pass mark the caller compares
            ``worst`` with: a positive finite number), a result of another problem.
    """
    if not 0.0 < tolerance < np.inf:  # NaN fails too: every comparison with it would pass or fail silently
        raise ExciteError("tolerance", f"{tolerance:g} is not a relative error", tolerance, "a number > 0")
    for name in objectives:
        if name not in OBJECTIVES:
            raise ExciteError("objective", f"'{name}' is not a criterion", name, f"one of {', '.join(OBJECTIVES)}")
    if not 0 <= seed <= MAX_SEED:
        raise ExciteError("seed", f"{seed} is out of range", seed, f"an integer from 0 to {MAX_SEED}")
    if not 1e-12 <= step <= 1e-2:
        raise ExciteError(
            "step", f"{step:g} is not a finite-difference step for coefficients in rad", step, "1e-12 to 1e-2"
        )
    excitation = build_excitation(problem)
    m = excitation.trajectory.n_coefficients
    points = [("random", None, excitation.limits.random_start(m, np.random.default_rng(seed), fill=0.7))]
    if result is not None:
        finished = read_iterations(result, excitation, field="result")
        stacked = stacked_regressors(excitation, None, finished[:-1])
        points.append((f"optimum {finished[-1].index}", stacked, finished[-1].alpha))
    gradients = []
    for label, prior, alpha in points:
        for name in objectives:
            criterion = excitation.criterion(prior, name)
            gradients.append((label, name, check_gradient(criterion, alpha, step=step)))
    lively = excitation.limits.random_start(m, np.random.default_rng(seed), 0.9, excitation.home)
    jacobians = [
        (c.name, c.evaluate(lively)[0].size, constraint_jacobian_error(c, lively)) for c in excitation.constraints
    ]
    return Verification(gradients, jacobians)
