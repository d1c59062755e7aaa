"""The interface every constraint shares (value and Jacobian in α), so the optimizer is generic."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from excite_cli.trajectory import FourierBasis


@dataclass(frozen=True)
class FineCheck:
    """Result of re-checking a trajectory on a fine grid.

    Attributes:
        max_violation: largest violation, normalized (dimensionless, ≤ 0 means satisfied).
        details: named figures with units in the name (e.g. ``max_violation_velocity_rad_s``).
    """

    max_violation: float
    details: dict[str, float]


class Constraint(ABC):
    """Inequalities g(α) ≤ 0 on the Fourier coefficients α (n, 2N+1), evaluated on the constraint grid.

    Attributes:
        name: short identifier.
        slack: largest value of g at which the constraint still holds on the grid (g carries a
            margin). SQP iterates approach the boundary from outside; points with g ≤ slack are
            accepted as feasible.
    """

    name: str
    slack: float = 0.0

    @abstractmethod
    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Values g (m,) and Jacobian ∂g/∂α (m, α.size), α flattened row-major."""

    @abstractmethod
    def check(self, alpha: np.ndarray, basis: FourierBasis) -> FineCheck:
        """Exact (not aggregated) re-check of α on the instants of ``basis``."""
