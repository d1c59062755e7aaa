"""Physically consistent identification: standard parameters φ (10 per body) and effect coefficients θ
that fit the torques, with every body's pseudo-inertia positive definite.

Per body, with pinocchio's parameters φ_i = [m, h_x, h_y, h_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz]
(h = m c, I the rotational inertia about the body frame's origin), the pseudo-inertia is

    J_i = [[Σ, h], [hᵀ, m]],  Σ = ½ tr(I) 𝟙 − I  (the second moment ∫ x xᵀ dm),

and J_i ≻ 0 is exactly "some positive mass distribution has these parameters": m > 0, I_c ≻ 0 and
the triangle inequalities of its principal moments (Wensing, Kim, Slotine, "Linear matrix inequalities
for physically consistent inertial parameter identification", RA-L 2017). The problem

    min_φ,θ  (1/M) ‖W (Y_B K φ + E θ − τ)‖² + λ ‖D⁻¹ (φ − φ_URDF)‖²
    s.t.     J_i(φ_i) ⪰ ε_i 𝟙 for every body,  θ_k ≥ 0 for Coulomb, viscous and armature coefficients

is a semidefinite program (solved by cvxpy with Clarabel); Y_B K φ = Y φ (Eq. 2), W the per-joint
weights of the weighted least-squares fit. D scales each body's parameters by its URDF mass m₀ (and
m₀ℓ, m₀ℓ² with ℓ = ``LENGTH``), so λ is dimensionless; it picks, among equally good fits, the
consistent one closest to the CAD model (the regularization of Sousa & Cortesão, IJRR 2014, and
Lee et al., RA-L 2020, in a Euclidean metric). The data term enters through a QR factor of the
weighted design matrix, so the SDP has only as many unknowns as parameters.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import cvxpy as cp
import numpy as np
import pinocchio as pin

from excite_cli.errors import ExciteError

#: Length scale ℓ [m] of the inertia parameters in the regularization.
LENGTH = 0.1
#: ε_i = this × m₀ ℓ²: the smallest eigenvalue kept by each pseudo-inertia [kg·m²].
MARGIN = 1e-5
#: A pseudo-inertia whose smallest eigenvalue is below this many ε_i is reported as active.
ACTIVE = 10.0
#: Effect coefficients that must not be negative.
NONNEGATIVE = ("Fc", "Fv", "Ia")


def pseudo_inertia(phi: np.ndarray) -> np.ndarray:
    """(4, 4) pseudo-inertia J [kg, kg·m, kg·m²] of one body's 10 parameters (module docstring)."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = phi
    I = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    J = np.zeros((4, 4))
    J[:3, :3] = 0.5 * np.trace(I) * np.eye(3) - I
    J[:3, 3] = J[3, :3] = [hx, hy, hz]
    J[3, 3] = m
    return J


def body_properties(phi: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """Mass [kg], centre of mass (3,) [m] and inertia about it (3, 3) [kg·m²] in the body frame's
    axes, and its principal moments (3,) [kg·m²] ascending, of one body's 10 parameters."""
    inertia = pin.Inertia.FromDynamicParameters(np.asarray(phi, dtype=float))
    I = inertia.inertia.copy()
    return float(inertia.mass), inertia.lever.copy(), I, np.linalg.eigvalsh(I)


def _pseudo_inertia_expression(phi) -> cp.Expression:
    """The same as :func:`pseudo_inertia` for a cvxpy vector of 10 (affine in φ)."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = (phi[k] for k in range(10))
    half = 0.5 * (ixx + iyy + izz)
    return cp.bmat(
        [[half - ixx, -ixy, -ixz, hx], [-ixy, half - iyy, -iyz, hy], [-ixz, -iyz, half - izz, hz], [hx, hy, hz, m]]
    )


@dataclass(frozen=True)
class ConsistentFit:
    """A physically consistent fit.

    Attributes:
        standard: (p,) standard parameters φ [kg, kg·m, kg·m²], 10 per body (pinocchio's order).
        effects: (k,) effect coefficients θ, in the design's column order.
        base: (b,) base parameters K φ (Eq. 2).
        min_eigenvalues: (bodies,) smallest eigenvalue of each pseudo-inertia [kg·m²].
        active: the constraints at their bound, in words (e.g. ``pseudo-inertia of panda_link7``).
        status: the solver's status (``optimal``, or ``optimal_inaccurate`` when Clarabel stopped
            at its reduced tolerances, typically with several constraints active).
        unconstrained: (p,) the same problem's solution without the constraints (regularized least
            squares: what plain least squares says about the standard parameters).
    """

    standard: np.ndarray
    effects: np.ndarray
    base: np.ndarray
    min_eigenvalues: np.ndarray
    active: list[str]
    status: str
    unconstrained: np.ndarray


def body_scales(phi_urdf: np.ndarray) -> np.ndarray:
    """(p,) scale D of each standard parameter: m₀, m₀ℓ (×3), m₀ℓ² (×6) per body, m₀ the URDF mass
    (at least 10 g)."""
    mass = np.maximum(phi_urdf[0::10], 0.01)
    pattern = np.array([1.0] + [LENGTH] * 3 + [LENGTH**2] * 6)
    return (mass[:, None] * pattern[None, :]).ravel()


def _solve(problem: cp.Problem) -> cp.Problem:
    """Solve with Clarabel; an inaccurate solution is reported in the status, not as a warning.

    Raises:
        ExciteError: the solver failed or found no (accurate or inaccurate) optimum.
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            problem.solve(solver=cp.CLARABEL)
    except cp.SolverError as exc:
        raise ExciteError("identification.physical_consistency", f"the SDP solver failed: {exc}") from None
    if problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
        raise ExciteError("identification.physical_consistency", f"the SDP ended {problem.status}")
    return problem


def consistent_fit(
    regressor: np.ndarray,
    effects: np.ndarray,
    tau: np.ndarray,
    weights: np.ndarray,
    regrouping: np.ndarray,
    phi_urdf: np.ndarray,
    effect_names: list[str],
    regularization: float,
    bodies: list[str],
) -> ConsistentFit:
    """Solve the semidefinite program of the module docstring.

    Args:
        regressor: (M, b) base regressor Y_B; effects: (M, k) effect columns E; tau: (M,) torques [Nm].
        weights: (M,) row weights W (1/σ_j of each row's joint).
        regrouping: K (b, p), φ_B = K φ; phi_urdf: (p,) the URDF's standard parameters.
        effect_names: (k,) ``"<coefficient> <joint>"`` of each effect column (e.g. ``"Fc panda_joint1"``);
            coefficients named in ``NONNEGATIVE`` are kept ≥ 0.
        regularization: λ ≥ 0.
        bodies: (p/10,) body names, for the ``active`` list.

    Raises:
        ExciteError: the solver finds no solution (the message gives its status).
    """
    scale = body_scales(phi_urdf)
    k = effects.shape[1]
    nonnegative = np.array([name.split()[0] in NONNEGATIVE for name in effect_names], dtype=bool)
    design = weights[:, None] * np.hstack([regressor @ regrouping * scale, effects])
    column = np.linalg.norm(design, axis=0)
    unseen = column <= 1e-9 * column.max()  # standard parameters the torques do not see (null space of K)
    design[:, unseen], column[unseen] = 0.0, 1.0
    target = weights * (tau - regressor @ (regrouping @ phi_urdf))
    Q, R = np.linalg.qr(design / column)
    z = Q.T @ target
    rows = tau.size
    u = cp.Variable(design.shape[1])  # u = column ⊙ [δ; θ], φ = φ_URDF + D δ
    delta = cp.multiply(u[: scale.size], 1.0 / column[: scale.size])
    theta = cp.multiply(u[scale.size :], 1.0 / column[scale.size :]) if k else None
    phi = phi_urdf + cp.multiply(scale, delta)
    epsilon = MARGIN * scale[0::10] * LENGTH**2
    # T J T ⪰ ε T² with T = diag(1/ℓ, 1/ℓ, 1/ℓ, 1)/√m₀: a congruence, same cone, entries of order 1
    T = np.diag([1.0 / LENGTH] * 3 + [1.0])
    constraints = [
        T @ _pseudo_inertia_expression(phi[10 * i : 10 * i + 10]) @ T / scale[10 * i]
        >> MARGIN * np.diag([1.0] * 3 + [LENGTH**2])
        for i in range(len(bodies))
    ]
    if k and nonnegative.any():
        constraints.append(theta[np.flatnonzero(nonnegative)] >= 0)
    objective = cp.sum_squares(R @ u - z) / rows + regularization * cp.sum_squares(delta)
    problem = _solve(cp.Problem(cp.Minimize(objective), constraints))
    standard = phi_urdf + scale * (u.value[: scale.size] / column[: scale.size])
    coefficients = u.value[scale.size :] / column[scale.size :]
    eigen = np.array(
        [np.linalg.eigvalsh(pseudo_inertia(standard[10 * i : 10 * i + 10]))[0] for i in range(len(bodies))]
    )
    if np.any(eigen <= 0.0):
        raise ExciteError(
            "identification.physical_consistency",
            f"the SDP ended {problem.status} with a pseudo-inertia "
            f"that is not positive definite (body {bodies[int(np.argmin(eigen))]})",
        )
    active = [f"pseudo-inertia of {name}" for name, e, eps in zip(bodies, eigen, epsilon) if e <= ACTIVE * eps]
    active += [f"{effect_names[c]} ≥ 0" for c in np.flatnonzero(nonnegative & (coefficients <= 1e-9))]
    stacked = np.vstack([R / np.sqrt(rows), np.sqrt(regularization) * np.diag(1.0 / column)[: scale.size]])
    plain = np.linalg.lstsq(stacked, np.concatenate([z / np.sqrt(rows), np.zeros(scale.size)]), rcond=None)[0]
    unconstrained = phi_urdf + scale * plain[: scale.size] / column[: scale.size]
    return ConsistentFit(
        standard, coefficients, regrouping @ standard, eigen, active, str(problem.status), unconstrained
    )
