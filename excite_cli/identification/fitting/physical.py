"""Physically consistent identification: standard parameters φ (10 per body) and effect coefficients θ
that fit the torques, with every body's pseudo-inertia positive definite.

Per body, with pinocchio's parameters φ_i = [m, h_x, h_y, h_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz]
(h = m c, I the rotational inertia about the body frame's origin), the pseudo-inertia is

    J_i = [[Σ, h], [hᵀ, m]],  Σ = ½ tr(I) 𝟙 − I  (the second moment ∫ x xᵀ dm),

and J_i ≻ 0 is exactly "some positive mass distribution has these parameters": m > 0, I_c ≻ 0 and
the triangle inequalities of its principal moments (Wensing, Kim, Slotine, "Linear matrix inequalities
for physically consistent inertial parameter identification", RA-L 2017). The problem

    min_φ,a,θ  (1/M) ‖W (Y_B (K φ + R a) + E θ − τ)‖² + λ ‖D⁻¹ (φ − φ_URDF)‖²
    s.t.       J_i(φ_i) ⪰ ε_i 𝟙 for every body,  a ≥ 0,  θ_k ≥ 0 for Coulomb, viscous and armature coefficients

is a semidefinite program (solved by cvxpy with Clarabel); Y_B K φ = Y φ (Eq. 2), W the per-joint
weights of the weighted least-squares fit. D scales each body's parameters by its URDF mass m₀ (and
m₀ℓ, m₀ℓ² with ℓ = ``LENGTH``), so λ is dimensionless; it picks, among equally good fits, the
consistent one closest to the CAD model (the regularization of Sousa & Cortesão, IJRR 2014, and
Lee et al., RA-L 2020, in a Euclidean metric). The data term enters through the weighted normal
equations of [Y_B, E] (a factor of them), so the SDP has only as many unknowns as parameters and
a cross-validation fold costs no design matrix.

The rotors a [kg·m²] are the armature of the joints whose rotor inertia regroups with a link's in the
base parameters (R, :func:`~excite_cli.dynamics.base_parameters.rotor_regrouping`: a serial arm's
first joints), parameters of their own beside the bodies (Wensing, Kim, Slotine 2017 identify rotors
with the links the same way). Least squares cannot tell a rotor from the link inertia it regroups
with; without a, the consistent fit must put a geared joint's rotor into the links' inertias, pulled
toward the URDF, and bend the bodies (a simulated Panda with 0.3 kg·m² on joints 1 and 2: link 3's
mass 39 % low). The prior does not pull a, so the regrouped base parameter holds what the data say
and the bodies stay near the URDF where the data do not move them.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import cvxpy as cp
import numpy as np
import pinocchio as pin

from excite_cli.effects import NONNEGATIVE
from excite_cli.errors import ExciteError
from excite_cli.identification.fitting.normal import square_root

#: Length scale ℓ [m] of the inertia parameters in the regularization.
LENGTH = 0.1
#: ε_i = this × m₀ ℓ²: the smallest eigenvalue kept by each pseudo-inertia [kg·m²].
MARGIN = 1e-5
#: A pseudo-inertia whose smallest eigenvalue is below this many ε_i is reported as active.
ACTIVE = 10.0


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
        base: (b,) base parameters K φ + R a (Eq. 2; the bodies and the rotors regrouped with them).
        rotors: (r,) rotor inertias a [kg·m²] of the joints ``rotor_joints`` (module docstring).
        rotor_joints: (r,) the joints whose rotors are held apart from the bodies.
        bodies_base: (b,) the bodies' part of ``base``, K φ (what a URDF of ``standard`` has).
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
    rotors: np.ndarray
    rotor_joints: list[str]
    bodies_base: np.ndarray


def nearest_physical(phi: np.ndarray) -> np.ndarray:
    """(p,) standard parameters with every body some mass distribution can have: a body whose
    pseudo-inertia is not positive definite (a vendor URDF whose principal moments break the triangle
    inequality) keeps its mass and centre of mass, and its second moment about the centre of mass,
    Σ_c = Σ − h hᵀ/m, gets its negative eigenvalues raised to a small positive floor (the nearest
    positive semidefinite matrix in the Frobenius norm, Higham 1988). Physical bodies are returned
    unchanged.

    Args:
        phi: (p,) pinocchio's standard parameters, 10 per body (module docstring).

    Returns:
        (p,) the projected parameters; a massless or negative-mass body gets 10 g at its frame origin.
    """
    out = np.array(phi, dtype=float)
    for body in out.reshape(-1, 10):
        if np.linalg.eigvalsh(pseudo_inertia(body))[0] > 0.0:
            continue
        m = max(body[0], 0.01)
        h = body[1:4] if body[0] > 0.0 else np.zeros(3)
        c = h / m
        J = pseudo_inertia(body)
        sigma_c = J[:3, :3] - np.outer(h, h) / m
        floor = 2.0 * MARGIN * m * LENGTH**2 * (1.0 + c @ c / LENGTH**2)  # above the SDP's ε_i (module docstring)
        w, V = np.linalg.eigh(0.5 * (sigma_c + sigma_c.T))
        sigma = (V * np.maximum(w, floor)) @ V.T + np.outer(h, h) / m
        inertia = np.trace(sigma) * np.eye(3) - sigma
        body[:] = [m, *h, inertia[0, 0], inertia[0, 1], inertia[1, 1], inertia[0, 2], inertia[1, 2], inertia[2, 2]]
    return out


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
        raise ExciteError("identification.fit", f"the SDP solver failed: {exc}") from None
    if problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
        raise ExciteError("identification.fit", f"the SDP ended {problem.status}")
    return problem


class ConsistentProgram:
    """The semidefinite program of the module docstring for one model, compiled once (cvxpy
    parameters) and solved for any normal equations of its unknowns and any λ: the fit on all data
    and each cross-validation fold's refit differ only in G, c and λ.

    Args:
        reference: (b + k, b + k) weighted normal equations AᵀW²A of A = [Y_B, E], the base regressor
            and the effect columns, on all fit data: they fix the unknowns' scaling and which
            standard parameters the torques never see (null space of K).
        regrouping: K (b, p), φ_B = K φ; phi_urdf: (p,) the URDF's standard parameters (a body no
            mass distribution can have is replaced by :func:`nearest_physical`'s).
        effect_names: (k,) ``"<coefficient> <joint>"`` of each effect column (e.g. ``"Fc panda_joint1"``);
            coefficients named in ``NONNEGATIVE`` are kept ≥ 0.
        bodies: (p/10,) body names, for the ``active`` list.
        rotors: {joint: (b,) column of R}: the joints whose rotor inertia regroups with the bodies',
            each kept ≥ 0 as a parameter of its own (module docstring; default none).
    """

    def __init__(
        self,
        reference: np.ndarray,
        regrouping: np.ndarray,
        phi_urdf: np.ndarray,
        effect_names: list[str],
        bodies: list[str],
        rotors: dict[str, np.ndarray] | None = None,
    ):
        phi_urdf = nearest_physical(phi_urdf)  # unseen parameters stay at φ_URDF: it must be feasible
        self.regrouping, self.phi_urdf, self.names, self.bodies = regrouping, phi_urdf, effect_names, bodies
        self.scale = scale = body_scales(phi_urdf)
        b, k, p = regrouping.shape[0], len(effect_names), scale.size
        self.rotor_joints = list(rotors or {})
        self.rotors = np.column_stack([rotors[j] for j in self.rotor_joints]) if rotors else np.zeros((b, 0))
        self.first_effect = p + (r := len(self.rotor_joints))  # [δ; a] come before the effects θ
        self.nonnegative = np.array([name.split()[0] in NONNEGATIVE for name in effect_names], dtype=bool)
        # [Y_B K D, Y_B R, E]: the design in the unknowns [δ; a; θ], φ = φ_URDF + D δ
        self.to_unknowns = np.zeros((b + k, p + r + k))
        self.to_unknowns[:b, :p] = regrouping * scale
        self.to_unknowns[:b, p : p + r] = self.rotors
        self.to_unknowns[b:, p + r :] = np.eye(k)
        column = np.sqrt(np.maximum(np.diag(self.to_unknowns.T @ reference @ self.to_unknowns), 0.0))
        self.unseen = column <= 1e-9 * column.max()
        column[self.unseen] = 1.0
        self.column = column
        size = p + r + k
        self.R, self.z = cp.Parameter((size, size)), cp.Parameter(size)  # the data term ‖R u − z‖², scaled by 1/M
        self.weight, self.pinned = cp.Parameter(nonneg=True), cp.Parameter(k, nonneg=True)
        self.u = u = cp.Variable(size)  # u = column ⊙ [δ; a; θ]
        delta = cp.multiply(u[:p], 1.0 / column[:p])
        phi = phi_urdf + cp.multiply(scale, delta)
        # T J T ⪰ ε T² with T = diag(1/ℓ, 1/ℓ, 1/ℓ, 1)/√m₀: a congruence, same cone, entries of order 1
        T = np.diag([1.0 / LENGTH] * 3 + [1.0])
        constraints = [
            T @ _pseudo_inertia_expression(phi[10 * i : 10 * i + 10]) @ T / scale[10 * i]
            >> MARGIN * np.diag([1.0] * 3 + [LENGTH**2])
            for i in range(len(bodies))
        ]
        if r:
            constraints.append(u[p : p + r] >= 0)
        if k and self.nonnegative.any():
            constraints.append(u[p + r + np.flatnonzero(self.nonnegative)] >= 0)
        if k:  # an effect column a fold's data never see (a held-out run's offset) is kept at 0
            constraints.append(cp.multiply(self.pinned, u[p + r :]) == 0)
        objective = cp.sum_squares(self.R @ u - self.z) + self.weight * cp.sum_squares(delta)
        self.problem = cp.Problem(cp.Minimize(objective), constraints)

    def solve(self, G: np.ndarray, c: np.ndarray, rows: int, regularization: float) -> ConsistentFit:
        """The consistent fit to the weighted normal equations G (b + k, b + k), c (b + k,) of ``rows``
        rows, with regularization λ ≥ 0.

        Raises:
            ExciteError: the solver finds no solution (the message gives its status).
        """
        b, p, q = self.regrouping.shape[0], self.scale.size, self.first_effect
        column = self.column
        normal = self.to_unknowns.T @ G @ self.to_unknowns / np.outer(column, column)
        right = self.to_unknowns.T @ (c - G[:, :b] @ (self.regrouping @ self.phi_urdf)) / column
        normal[self.unseen, :], normal[:, self.unseen] = 0.0, 0.0
        A, b = square_root(normal, right)
        R, z = np.zeros_like(normal), np.zeros(normal.shape[0])  # RᵀR = the scaled normal matrix (padded)
        R[: len(A)], z[: len(b)] = A, b
        self.R.value, self.z.value, self.weight.value = R / np.sqrt(rows), z / np.sqrt(rows), regularization
        self.pinned.value = (np.diag(normal)[q:] <= 0.0).astype(float)
        problem = _solve(self.problem)
        u = self.u.value
        standard = self.phi_urdf + self.scale * (u[:p] / column[:p])
        rotors, coefficients = u[p:q] / column[p:q], u[q:] / column[q:]
        eigen = np.array(
            [np.linalg.eigvalsh(pseudo_inertia(standard[10 * i : 10 * i + 10]))[0] for i in range(len(self.bodies))]
        )
        if np.any(eigen <= 0.0):
            raise ExciteError(
                "identification.fit",
                f"the SDP ended {problem.status} with a pseudo-inertia "
                f"that is not positive definite (body {self.bodies[int(np.argmin(eigen))]})",
            )
        epsilon = MARGIN * self.scale[0::10] * LENGTH**2
        active = [f"pseudo-inertia of {name}" for name, e, eps in zip(self.bodies, eigen, epsilon) if e <= ACTIVE * eps]
        active += [f"{self.names[c]} ≥ 0" for c in np.flatnonzero(self.nonnegative & (coefficients <= 1e-9))]
        active += [f"rotor of {j} ≥ 0" for j, a in zip(self.rotor_joints, rotors) if a <= 1e-9]
        stacked = np.vstack([R / np.sqrt(rows), np.sqrt(regularization) * np.diag(1.0 / column)[:p]])
        plain = np.linalg.lstsq(stacked, np.concatenate([z / np.sqrt(rows), np.zeros(p)]), rcond=None)[0]
        unconstrained = self.phi_urdf + self.scale * plain[:p] / column[:p]
        bodies = self.regrouping @ standard
        return ConsistentFit(
            standard,
            coefficients,
            bodies + self.rotors @ rotors,
            eigen,
            active,
            str(problem.status),
            unconstrained,
            rotors,
            self.rotor_joints,
            bodies,
        )
