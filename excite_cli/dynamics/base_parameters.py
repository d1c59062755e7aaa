"""Base parameters and the composition matrix (Eq. 2), by Gram-Schmidt with column pivoting and a
pivot rule that rounding cannot change.

The regressor W of many random states is orthogonalized column by column, each step taking the
column with the largest residual norm (Gautier 1991, "Numerical calculation of the base inertial
parameters of robots": QR with column pivoting). The first b pivoted columns are independent; the
others are linear combinations of them, W_d = W_i β. Then

    Y φ = Y_i (φ_i + β φ_d) = (Y X) φ_B,

where X (p × b) selects the independent columns (the composition matrix of Eq. 2) and
φ_B = K φ with K (b × p) = [I β] in pivoted order.

Symmetric robots (a humanoid's two arms) and the regrouping rules themselves give columns whose
residual norms are equal in exact arithmetic: which one plain pivoted QR takes is then decided by
rounding, which differs with the BLAS kernel, its threads and the processor, and a different choice
is a different base (another cond(C), other names). Here residual norms within ``TIE_TOLERANCE`` of
the largest are a tie, and a tie goes to the standard parameter that comes first in the robot's
parameter order (bodies in model order, then m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz): the base
is a function of the robot, not of the machine, nor of the order of the rows or columns of W.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.linalg

from excite_cli.dynamics.robot import Robot
from excite_cli.dynamics.urdf_rounding import ROUNDING_FACTOR
from excite_cli.errors import ExciteError, ExciteWarning

#: A residual column norm below this fraction of the first pivot's is rank loss.
RANK_TOLERANCE = 1e-9
#: Residual norms within this relative distance of the largest are a tie (exact ties differ by rounding,
#: about 1e-14; columns that are not tied differ by far more).
TIE_TOLERANCE = 1e-6
#: Regrouping coefficients below this are zero (rounding of exact zeros).
ZERO_TOLERANCE = 1e-9
#: Significant digits regrouping coefficients are rounded to. They are products of the URDF's
#: lengths (a few digits each), so rounding removes only the last bits, which depend on the BLAS
#: library, and names and K come out the same on every machine.
SIGNIFICANT_DIGITS = 10


@dataclass(frozen=True)
class BaseParameters:
    """Composition matrix and regrouping of a robot's standard parameters.

    Attributes:
        composition_matrix: X, (p, b): Y_B = Y X (Eq. 2).
        regrouping: K, (b, p): φ_B = K φ.
        names: (b,) readable names, e.g. ``Izz_link2 + 0.09·m_link3``.
        independent: (b,) indices of the standard parameters X selects: Y_B = Y[:, independent].

    The arrays are read-only copies: one base is shared by every user in a process, and shipped to
    every worker.
    """

    composition_matrix: np.ndarray
    regrouping: np.ndarray
    names: list[str]
    independent: np.ndarray

    def __post_init__(self) -> None:
        for name in ("composition_matrix", "regrouping", "independent"):
            value = np.array(getattr(self, name))
            value.flags.writeable = False
            object.__setattr__(self, name, value)

    @property
    def count(self) -> int:
        """Number b of base parameters."""
        return self.composition_matrix.shape[1]

    def from_standard(self, phi: np.ndarray) -> np.ndarray:
        """Base parameters φ_B = K φ: (b,) from standard parameters (p,)."""
        return self.regrouping @ phi

    def column_order(self, names: Sequence[str], field: str, source: object) -> np.ndarray:
        """Where each of these base parameters sits among ``names``, the base-parameter names stored
        with columns read from a file: ``columns[:, order]`` are in this base's order (b,).

        Raises:
            ExciteError: (``field``) ``names`` are other base parameters (another robot, joint set
                or base), naming the first of them that this base does not have.
        """
        where = {name: k for k, name in enumerate(names)}
        if len(where) == len(names) == self.count and set(where) == set(self.names):
            return np.array([where[name] for name in self.names], dtype=int)
        other = next((n for n in names if n not in set(self.names)), None)
        detail = f"'{other}' is not one of the problem's" if other else f"{len(names)} instead of {self.count}"
        raise ExciteError(field, f"{source} was made for another problem: other base parameters ({detail})")


def pivoted_columns(W: np.ndarray, order: np.ndarray, tolerance: float = RANK_TOLERANCE) -> list[int]:
    """Independent columns of W (m, p) in pivot order: Gram-Schmidt (twice per step, so the residuals
    stay orthogonal to the chosen columns) taking at each step the column of largest residual norm;
    norms within ``TIE_TOLERANCE`` of it are a tie, won by the lowest ``order`` (p,) rank.

    Stops at the first residual norm below ``tolerance`` times the first pivot's.
    """
    residual = np.array(W, dtype=float, copy=True)
    norms = np.sqrt(np.einsum("ij,ij->j", residual, residual))
    if norms.size == 0 or norms.max() == 0.0:
        return []
    floor = tolerance * norms.max()
    chosen: list[int] = []
    units = np.zeros((W.shape[0], 0))
    for _ in range(min(W.shape)):
        norms[chosen] = -1.0
        top = norms.max()
        if top <= floor:
            break
        ties = np.flatnonzero(norms >= (1.0 - TIE_TOLERANCE) * top)
        j = int(ties[np.argmin(order[ties])])
        chosen.append(j)
        unit = residual[:, j] - units @ (units.T @ residual[:, j])
        unit /= np.linalg.norm(unit)
        for _ in range(2):
            residual -= np.outer(unit, unit @ residual)
        units = np.column_stack([units, unit])
        norms = np.sqrt(np.einsum("ij,ij->j", residual, residual))
    return chosen


def _rounded(beta: np.ndarray) -> np.ndarray:
    """Regrouping coefficients rounded to ``SIGNIFICANT_DIGITS`` (Python's correctly rounded
    formatting, the same everywhere), those below ``ZERO_TOLERANCE`` set to 0."""
    flat = [0.0 if abs(x) <= ZERO_TOLERANCE else float(f"{x:.{SIGNIFICANT_DIGITS}g}") for x in beta.ravel()]
    return np.array(flat).reshape(beta.shape)


def _name(row: np.ndarray, names: list[str], lead: int, order: np.ndarray) -> str:
    """``names[lead]`` followed by the other standard parameters regrouped into it, in ``order``."""
    parts = [names[lead]]
    for k in sorted(np.flatnonzero(row), key=lambda k: order[k]):
        if k != lead:
            parts.append(f"{'-' if row[k] < 0 else '+'} {abs(row[k]):.4g}·{names[k]}")
    return " ".join(parts)


def base_from_regressor(
    W: np.ndarray, names: list[str], order: np.ndarray | None = None, tolerance: float = RANK_TOLERANCE
) -> BaseParameters:
    """Base parameters of the standard regressor rows W (m, p) whose columns are the parameters
    ``names`` (p,), ties broken by ``order`` (p,), each column's rank in the robot's parameter order
    (default: the columns' own order; module docstring); residual norms below ``tolerance`` times the
    largest are rank loss.

    Raises:
        ExciteError: no parameter is excited by the rows (b = 0).
    """
    p = W.shape[1]
    order = np.arange(p) if order is None else np.asarray(order)
    independent = np.array(pivoted_columns(W, order, tolerance), dtype=int)
    if independent.size == 0:
        raise ExciteError("robot.active_joints", "no inertial parameter affects the selected regressor rows")
    b = independent.size
    dependent = np.setdiff1d(np.arange(p), independent)
    beta = _rounded(scipy.linalg.lstsq(W[:, independent], W[:, dependent])[0]) if dependent.size else np.zeros((b, 0))
    X = np.zeros((p, b))
    X[independent, np.arange(b)] = 1.0
    K = np.zeros((b, p))
    K[np.arange(b), independent] = 1.0
    K[:, dependent] = beta
    labels = [_name(K[i], names, independent[i], order) for i in range(b)]
    return BaseParameters(composition_matrix=X, regrouping=K, names=labels, independent=independent)


def compute_base_parameters(robot: Robot, seed: int = 0, samples: int | None = None) -> BaseParameters:
    """Numerical base parameters of ``robot`` from a regressor of random states (:func:`base_from_regressor`),
    at the rank tolerance of the URDF's rounding (:mod:`excite_cli.dynamics.urdf_rounding`): the
    directions it drops are said in an :class:`~excite_cli.errors.ExciteWarning`.

    The same on every processor, BLAS library and thread count: compute it once and pass it on.

    Args:
        robot: the robot.
        seed: seed of the random states.
        samples: number of random states (default: enough for 3× more rows than parameters).

    Returns:
        The :class:`BaseParameters`, in pivot order.

    Raises:
        ExciteError: no parameter is excited by the regressor rows (b = 0).
    """
    W = robot.regressor_stack(*_random_states(robot, seed, samples))
    tolerance = max(RANK_TOLERANCE, ROUNDING_FACTOR * robot.angle_rounding)
    base = base_from_regressor(W, robot.parameter_names, tolerance=tolerance)
    if tolerance > RANK_TOLERANCE:
        dropped = len(pivoted_columns(W, np.arange(W.shape[1]))) - base.count
        if dropped:
            warnings.warn(
                f"robot: {dropped} direction(s) of the regressor below {tolerance:.2g} of the largest are not base "
                f"parameters ({base.count} are): the URDF writes right angles rounded (by up to "
                f"{robot.angle_rounding:.2g} rad), and what they add no motion excites above the rounding",
                ExciteWarning,
                stacklevel=2,
            )
    return base


def _random_states(robot: Robot, seed: int, samples: int | None = None) -> tuple[np.ndarray, ...]:
    """(samples, n) random positions, velocities and accelerations (default: enough for 3× more
    regressor rows than parameters)."""
    count = samples or max(20, int(np.ceil(3 * robot.n_parameters / robot.n_rows)))
    return robot.random_states(count, np.random.default_rng(seed))


def rotor_regrouping(robot: Robot, base: BaseParameters, seed: int = 0) -> np.ndarray:
    """How each joint's rotor inertia (armature I_a, the column q̈_j on joint j's torque row) regroups
    with the base parameters: R (b, n) with Y_B R[:, j] = that column at every state, or a zero column
    where it does not (its armature is then separately identifiable, an effect column of its own).

    A joint whose axis no link before it turns (a serial arm's first joints) has an armature that
    only adds to a regrouped link inertia (e.g. Izz of link 1), so least squares cannot tell the two
    apart; the physically consistent fit can, holding the rotor as a parameter of its own (Wensing,
    Kim, Slotine, RA-L 2017, identify rotors beside the links).

    Args:
        robot: the robot; base: its base parameters (:func:`compute_base_parameters`).
        seed: seed of the random states.

    Returns:
        (b, n) R, coefficients rounded as the regrouping's (``SIGNIFICANT_DIGITS``).
    """
    Q, QD, QDD = _random_states(robot, seed)
    count = Q.shape[0]
    Y_B = robot.regressor_stack(Q, QD, QDD)[:, base.independent]
    first = robot.n_rows - robot.n_joints  # the joints' rows follow the base wrench's, if any
    columns = np.zeros((count, robot.n_rows, robot.n_joints))
    columns[:, first + np.arange(robot.n_joints), np.arange(robot.n_joints)] = QDD
    columns = columns.reshape(-1, robot.n_joints)
    R = scipy.linalg.lstsq(Y_B, columns)[0]
    residual = np.linalg.norm(columns - Y_B @ R, axis=0)
    R[:, residual > RANK_TOLERANCE * np.linalg.norm(Y_B, axis=0).max()] = 0.0
    return _rounded(R)
