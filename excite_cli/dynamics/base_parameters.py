"""Base parameters and the composition matrix (Eq. 2), by QR decomposition with column pivoting.

The regressor W of many random states is decomposed as W P = Q R. The first b pivoted columns are
independent; the others are linear combinations of them, W_d = W_i β with β = R₁₁⁻¹ R₁₂. Then

    Y φ = Y_i (φ_i + β φ_d) = (Y X) φ_B,

where X (p × b) selects the independent columns (the composition matrix of Eq. 2) and
φ_B = K φ with K (b × p) = [I β] in pivoted order. (Gautier 1991, "Numerical calculation of the
base inertial parameters of robots".)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError

#: |R_kk| / |R_00| below this is rank loss.
RANK_TOLERANCE = 1e-9
#: Regrouping coefficients below this are shown as zero in names.
NAME_TOLERANCE = 1e-9


@dataclass(frozen=True)
class BaseParameters:
    """Composition matrix and regrouping of a robot's standard parameters.

    Attributes:
        composition_matrix: X, (p, b): Y_B = Y X (Eq. 2).
        regrouping: K, (b, p): φ_B = K φ.
        independent: (b,) indices of the standard parameters X selects: Y_B = Y[:, independent].
        names: (b,) readable names, e.g. ``Izz_link2 + 0.09·m_link3``.
    """

    composition_matrix: np.ndarray
    regrouping: np.ndarray
    names: list[str]
    independent: np.ndarray

    @property
    def count(self) -> int:
        """Number b of base parameters."""
        return self.composition_matrix.shape[1]

    def from_standard(self, phi: np.ndarray) -> np.ndarray:
        """Base parameters φ_B = K φ: (b,) from standard parameters (p,)."""
        return self.regrouping @ phi


def _name(row: np.ndarray, names: list[str], lead: int) -> str:
    """``names[lead]`` followed by the other standard parameters regrouped into it."""
    parts = [names[lead]]
    for k in np.flatnonzero(np.abs(row) > NAME_TOLERANCE):
        if k != lead:
            parts.append(f"{'-' if row[k] < 0 else '+'} {abs(row[k]):.4g}·{names[k]}")
    return " ".join(parts)


def compute_base_parameters(robot: Robot, seed: int = 0, samples: int | None = None) -> BaseParameters:
    """Numerical base parameters of ``robot`` from a regressor of random states.

    Args:
        robot: the robot.
        seed: seed of the random states.
        samples: number of random states (default: enough for 3× more rows than parameters).

    Returns:
        The :class:`BaseParameters`.

    Raises:
        ExciteError: no parameter is excited by the regressor rows (b = 0).
    """
    rng = np.random.default_rng(seed)
    p = robot.n_parameters
    count = samples or max(20, int(np.ceil(3 * p / robot.n_rows)))
    W = robot.regressor_stack(*robot.random_states(count, rng))
    _, R, perm = scipy.linalg.qr(W, mode="economic", pivoting=True)
    diag = np.abs(np.diag(R))
    b = int(np.sum(diag > RANK_TOLERANCE * diag[0])) if diag.size and diag[0] > 0 else 0
    if b == 0:
        raise ExciteError("robot.active_joints", "no inertial parameter affects the selected regressor rows")
    independent, dependent = perm[:b], perm[b:]
    beta = scipy.linalg.solve_triangular(R[:b, :b], R[:b, b:])
    X = np.zeros((p, b))
    X[independent, np.arange(b)] = 1.0
    K = np.zeros((b, p))
    K[np.arange(b), independent] = 1.0
    K[:, dependent] = beta
    names = robot.parameter_names
    labels = [_name(K[i], names, independent[i]) for i in range(b)]
    return BaseParameters(composition_matrix=X, regrouping=K, names=labels, independent=independent)
