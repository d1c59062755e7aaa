"""The interface every constraint shares (value and Jacobian in α), so the optimizer is generic."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from excite_cli.memo import once
from excite_cli.trajectory.fourier import FourierBasis


@dataclass(frozen=True)
class FineCheck:
    """Result of re-checking a trajectory on a fine grid.

    Attributes:
        max_violation: largest violation, normalized (dimensionless, ≤ 0 means satisfied).
        details: named figures with units in the name (e.g. ``max_violation_velocity_rad_s``), or
            names (e.g. ``min_capsule_pair``).
        where: where the worst sample is, in words (for messages).
    """

    max_violation: float
    details: dict[str, float | str]
    where: str = ""


class Constraint(ABC):
    """Inequalities g(α) ≤ 0 on the Fourier coefficients α (n, 2N+1), evaluated on the constraint grid.

    Attributes:
        name: short identifier.
        field: the config field a violation is reported under (e.g. ``constraints.com``).
        basis: Fourier basis on the constraint grid.
        grid_margin: normalized margin the exact grid samples must keep for α to be accepted; it
            covers the overshoot between grid instants.
        track_units: the unit of each series :meth:`track` returns, by name.
        needs_motion: whether only a moving trajectory can satisfy it (standing still at the home
            posture and the random starts need not; the solver moves into it).
        advisory: whether it predicts what the robot's own control decides (the zero-moment point, which
            the stance's compliance moves): the optimizer keeps it, ``export`` warns instead of refusing.
        eased_by_slowing: whether the same path played slower keeps it better (it bounds what the
            accelerations cause: |τ| ≤ τ_max, the zero-moment point): a transition
            (:mod:`~excite_cli.design.playback`) is lengthened until it holds.
        home_clearance: what a drafted home posture keeps beyond the margin of :meth:`clearance` [m].
    """

    name: str
    field: str
    basis: FourierBasis
    grid_margin: float = 0.0
    track_units: dict[str, str] = {}
    needs_motion: bool = False
    advisory: bool = False
    eased_by_slowing: bool = False
    home_clearance: float = 0.005
    capsules: Sequence = ()

    @abstractmethod
    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Values g (m,) and Jacobian ∂g/∂α (m, α.size), α flattened row-major."""

    def values(self, alpha: np.ndarray) -> np.ndarray:
        """Values g (m,) alone (what a line search's trial points need); constraints whose Jacobian
        costs much more than their values compute them without it."""
        return self._evaluated(alpha)[0]

    def jacobian(self, alpha: np.ndarray) -> np.ndarray:
        """Jacobian ∂g/∂α (m, α.size) of :meth:`evaluate`, computed once per point with the values."""
        return self._evaluated(alpha)[1]

    def _evaluated(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`evaluate` at α, or what it gave at the same α the last time (a solver asks for the
        values and then the Jacobian at the same point)."""
        return once(self, "evaluate", alpha, lambda: self.evaluate(alpha))

    @abstractmethod
    def check_samples(self, time: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> FineCheck:
        """Exact (not aggregated) check of sampled motion: ``time`` (T,) [s], q, q̇, q̈ (T, n) [rad, rad/s,
        rad/s²] (any motion, e.g. a transition or a file at the controller's rate)."""

    def check(self, alpha: np.ndarray, basis: FourierBasis) -> FineCheck:
        """Exact (not aggregated) re-check of α on the instants of ``basis``."""
        return self.check_samples(basis.time, *basis.evaluate(alpha))

    def accepts(self, alpha: np.ndarray) -> bool:
        """Whether α satisfies the constraint on the grid, exactly, with ``grid_margin`` to spare."""
        return self.check(alpha, self.basis).max_violation <= -self.grid_margin

    def in_words(self) -> str:
        """What its rows hold, in words (``check``); default: its config field."""
        return self.field

    def clearance(self, Q: np.ndarray) -> np.ndarray:
        """(K,) at each posture Q (K, n) [rad] the smallest distance [m] beyond its margin that it keeps
        (a distance constraint's; default inf: it keeps no distance)."""
        return np.full(len(Q), np.inf)

    def ground_point(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray | None:
        """(S, 2) the point on the ground [m] it predicts at the samples q, q̇, q̈ (S, n) (the zero-moment
        point's; default None: it predicts none), for comparison with a physics engine's centre of pressure."""
        return None

    def never_apart(self, Q: np.ndarray, apart: float) -> list[tuple[tuple[str, str], float]]:
        """Link pairs whose capsules are never farther apart than ``apart`` [m] at the postures Q
        (K, n) [rad], with the largest distance [m] (a self-collision's; default none): pairs no motion
        separates, which ``init`` excludes."""
        return []

    def out_of_reach(self) -> list[tuple[tuple[str, str], float]]:
        """Link pairs no motion brings within the margin, with a bound on their distance [m] (a
        self-collision's; default none): pairs ``init`` excludes, as they cost time and bind nothing."""
        return []

    def shapes_in_reach(self) -> list[str]:
        """The world shapes some moving capsule can come within the margin of (the world's; default
        none): the others add no rows, which ``check`` says."""
        return []

    def always_within(self, Q: np.ndarray) -> list[tuple[str, float]]:
        """Links within a world shape's margin at every posture Q (K, n) [rad], with that margin [m]
        (the world's; default none): links no motion moves off the shape, which ``init`` ignores."""
        return []

    def drawn(self) -> dict[str, object]:
        """What the constraint-tracks figure draws for it beside its tracks, as keyword arguments of
        :func:`~excite_cli.plots.tracks.plot_constraint_tracks` (default: nothing)."""
        return {}

    def track(self, alpha: np.ndarray, basis: FourierBasis) -> dict[str, np.ndarray]:
        """Named time series worth plotting and storing, on ``basis``'s instants (default: none)."""
        return {}

    def restore(self, alpha: np.ndarray) -> np.ndarray:
        """A nearby α that satisfies this constraint, where a cheap exact repair exists (default: α)."""
        return alpha


def accepted(constraints: Sequence[Constraint], alpha: np.ndarray, basis: FourierBasis | None = None) -> bool:
    """Whether every constraint accepts α (n, 2N+1): on its grid with its margin (:meth:`Constraint.accepts`),
    or, given a ``basis``, on its instants with no violation (the fine re-check a result is judged by)."""
    if basis is None:
        return all(c.accepts(alpha) for c in constraints)
    return all(c.check(alpha, basis).max_violation <= 0.0 for c in constraints)


def farthest_accepted(
    constraints: Sequence[Constraint], start: np.ndarray, end: np.ndarray, steps: int, basis: FourierBasis | None = None
) -> float:
    """The largest t ∈ [0, 1] that ``steps`` bisections find with start + t (end − start) accepted by
    every constraint (:func:`accepted`, on ``basis`` if given; ``start`` (n, 2N+1) is assumed accepted,
    t = 0 when nothing beyond it is)."""
    lo, hi = 0.0, 1.0
    for _ in range(steps):
        mid = (lo + hi) / 2.0
        lo, hi = (mid, hi) if accepted(constraints, start + mid * (end - start), basis) else (lo, mid)
    return lo
