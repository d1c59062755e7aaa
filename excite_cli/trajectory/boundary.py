"""Boundary conditions of the Fourier trajectory and the coordinates the optimizer works in.

``periodic`` is the paper's Eq. 50 as it is: the trajectory may start and end at full speed.
``rest`` asks q̇ = q̈ = 0 at t = 0 and t = T (T the trajectory's duration), and ``ends_at_home``
also q(0) = q(T) = the home posture. Eq. 50 is linear in α, so for joint j these are linear
equalities A α_jᵀ = c_j with the rows of A the Fourier basis B_q̇, B_q̈ (and B_q) at t = 0 and T.

They are satisfied exactly by a parameterization: with the optimizer's diagonal preconditioning s_j
(see :meth:`JointLimits.coefficient_scale`), α_j = s_j ⊙ (w*_j + Z_j z_j), where Z_j is an
orthonormal basis of the null space of A diag(s_j) and w*_j its minimum-norm particular solution.
The optimizer's variables are the z_j; every iterate meets the conditions to rounding error, and
the map is orthogonal in the preconditioned metric, so ``periodic`` (Z_j = I) is the plain
preconditioned problem.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import null_space

from excite_cli.config import TrajectoryConfig
from excite_cli.errors import ExciteError
from excite_cli.trajectory.fourier import FourierTrajectory

#: Singular values below this (relative) make a boundary row redundant (t = T a whole period).
RANK_TOLERANCE = 1e-10


def boundary_rows(trajectory: FourierTrajectory, duration: float, rest: bool, at_home: bool) -> np.ndarray:
    """Rows A (m, 2N+1) of the equalities A α_jᵀ = c_j: q̇ and q̈ at t = 0 and ``duration`` [s] with
    ``rest``, q at both ends with ``at_home``; (0, 2N+1) when neither."""
    basis = trajectory.basis(np.array([0.0, duration]))
    rows = ([basis.qd, basis.qdd] if rest else []) + ([basis.q] if at_home else [])
    return np.vstack(rows) if rows else np.zeros((0, trajectory.n_coefficients))


class BoundaryConditions:
    """The equalities of one problem and the optimizer's coordinates z that satisfy them exactly.

    Args:
        rows: A (m, 2N+1), see :func:`boundary_rows`.
        targets: (n, m) right-hand sides c_j: 0 for q̇, q̈ rows, the home posture [rad] for q rows.
        scale: (n, 2N+1) preconditioning s [rad] per coefficient.

    Raises:
        ValueError: shapes that do not match.
    """

    def __init__(self, rows: np.ndarray, targets: np.ndarray, scale: np.ndarray):
        n, m = scale.shape
        if rows.shape[1] != m or targets.shape != (n, rows.shape[0]):
            raise ValueError(f"boundary conditions: {rows.shape=}, {targets.shape=} for {scale.shape=}")
        self.rows, self.scale = rows, scale
        bases, particular = [], []
        for s, c in zip(scale, targets):
            scaled = rows * s
            bases.append(null_space(scaled, rcond=RANK_TOLERANCE) if rows.size else np.eye(m))
            particular.append(np.linalg.lstsq(scaled, c, rcond=RANK_TOLERANCE)[0] if rows.size else np.zeros(m))
        self.bases = np.stack(bases)  # (n, 2N+1, r)
        self.particular = np.stack(particular)  # (n, 2N+1)
        wave = rows[:, 1:]
        #: (2N, r') orthonormal basis of the oscillations (α_j without q0) that meet the conditions
        #: when q0 is the home posture: random starts are drawn in it.
        self.wave_space = null_space(wave, rcond=RANK_TOLERANCE) if rows.size else np.eye(m - 1)

    @property
    def size(self) -> int:
        """Number of optimizer variables, n·r."""
        return self.bases.shape[0] * self.bases.shape[2]

    def to_alpha(self, z: np.ndarray) -> np.ndarray:
        """α (n, 2N+1) [rad] of the flat variables z (n·r,)."""
        z = z.reshape(self.bases.shape[0], -1)
        return self.scale * (self.particular + np.einsum("jmr,jr->jm", self.bases, z))

    def to_variables(self, alpha: np.ndarray) -> np.ndarray:
        """Flat variables z (n·r,) of the point of the constrained set nearest to α (n, 2N+1) in the
        preconditioned metric (α itself when it meets the conditions)."""
        return np.einsum("jmr,jm->jr", self.bases, alpha / self.scale - self.particular).ravel()

    def project(self, alpha: np.ndarray) -> np.ndarray:
        """α (n, 2N+1) moved onto the conditions (nearest point, preconditioned metric)."""
        return self.to_alpha(self.to_variables(alpha))

    def chain(self, gradient: np.ndarray) -> np.ndarray:
        """Gradients in the variables (k, n·r) of gradients in α (k, n·(2N+1)) (or (n·(2N+1),) → (n·r,))."""
        g = np.asarray(gradient)
        n, m, r = self.bases.shape
        out = np.einsum("kjm,jmr->kjr", g.reshape(-1, n, m) * self.scale, self.bases)
        return out.reshape(g.shape[:-1] + (n * r,)) if g.ndim > 1 else out.ravel()  # k may be 0 (no rows)


def boundary_conditions(
    tcfg: TrajectoryConfig, trajectory: FourierTrajectory, scale: np.ndarray, home: np.ndarray
) -> BoundaryConditions:
    """The boundary conditions of ``trajectory.boundary`` / ``ends_at_home`` with the optimizer's
    preconditioning ``scale`` (n, 2N+1) [rad] and the home posture ``home`` (n,) [rad].

    Raises:
        ExciteError: the conditions leave the joints no oscillation (too few harmonics).
    """
    rows = boundary_rows(trajectory, tcfg.duration, tcfg.boundary == "rest", tcfg.ends_at_home)
    targets = np.zeros((home.size, rows.shape[0]))
    if tcfg.ends_at_home:
        targets[:, -2:] = home[:, None]
    boundary = BoundaryConditions(rows, targets, scale)
    if boundary.wave_space.shape[1] == 0:
        raise ExciteError(
            "trajectory.harmonics",
            f"{tcfg.harmonics} harmonic(s) leave no free oscillation under "
            f"boundary '{tcfg.boundary}'{' with ends_at_home' if tcfg.ends_at_home else ''}; use more harmonics",
        )
    return boundary
