"""Physically consistent identification: standard parameters φ (10 per body) and effect coefficients θ
that fit the torques, with every body's pseudo-inertia positive definite
(:mod:`~excite_cli.identification.fitting.bodies`). The problem

    min_φ,a,ψ,θ  (1/M) ‖W (Y_B (K (φ + P ψ) + R a) + E θ − τ)‖²
                 + λ (‖D⁻¹ (φ − φ_URDF)‖² + μ ‖D_P⁻¹ ψ‖²)
    s.t.         J_i(φ_i) ⪰ ε_i 𝟙 for every body,  J(ψ_l) ⪰ 0 for every payload,  a ≥ 0,
                 θ_k ≥ 0 for Coulomb, viscous and armature coefficients

is a semidefinite program (solved by cvxpy with Clarabel); Y_B K φ = Y φ (Eq. 2), W the per-joint
weights of the weighted least-squares fit. D scales each body's parameters by its URDF mass m₀ (and
m₀ℓ, m₀ℓ² with ℓ = ``LENGTH``), so λ is dimensionless; it picks, among equally good fits, the
consistent one closest to the CAD model (the regularization of Sousa & Cortesão, IJRR 2014, and
Lee et al., RA-L 2020, in a Euclidean metric). The data term enters through the weighted normal
equations of [Y_B, E] (a factor of them), so the SDP has only as many unknowns as parameters and
a cross-validation fold costs no design matrix.

Two kinds of parameters stand apart from the bodies, so that the bodies stay where the URDF has them
wherever the data do not move them (Wensing, Kim, Slotine 2017 identify rotors and loads beside the
links the same way):

- The rotors a [kg·m²]: the armature of the joints whose rotor inertia regroups with a link's in the
  base parameters (R, :func:`~excite_cli.dynamics.base_parameters.rotor_regrouping`: a serial arm's
  first joints). Least squares cannot tell a rotor from the link inertia it regroups with; without
  a, the consistent fit must put a geared joint's rotor into the links' inertias, pulled toward the
  URDF, and bend the bodies (a simulated Panda with 0.3 kg·m² on joints 1 and 2: link 3's mass 39 %
  low). The prior does not pull a. The other joints' rotors are effect columns of their own, kept ≥ 0
  like a (:mod:`~excite_cli.identification.choice.consistent_model`).
- The payloads ψ_l: a body of its own (10 parameters, a positive semidefinite pseudo-inertia: none
  at all is allowed) on each body that carries no other (a tool or load on the flange; P places it
  on its carrier), scaled like its carrier (D_P) and pulled toward none μ = ``PAYLOAD_PULL`` times
  as hard as the bodies toward the URDF. A mass on the flange regroups with the links below it (on
  the last joint's axis it changes only parameters shared with them), so the data do not say which
  body carries it; pulled as hard as the links, it was spread over them (MuJoCo's UR5 with 1.5 kg on
  the flange: links 4–5 +52 % and +81 %, the last −84 %). The payload takes what the links would
  have to bend for; what the data never see of it stays at none. The fit reports each payload and
  the carrier's parameters with it (what is on that link, what a URDF of the robot needs).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import cvxpy as cp
import numpy as np

from excite_cli.effects import NONNEGATIVE
from excite_cli.errors import ExciteError
from excite_cli.identification.fitting.bodies import (
    LENGTH,
    MARGIN,
    body_scales,
    nearest_physical,
    pseudo_inertia,
    pseudo_inertia_expression,
)
from excite_cli.identification.fitting.normal import square_root

#: A pseudo-inertia whose smallest eigenvalue is below this many ε_i is reported as active.
ACTIVE = 10.0
#: μ: how hard a payload is pulled toward none, relative to the bodies' pull toward the URDF. Weak, so
#: that among fits the data cannot tell apart the one that bends the links least is found (10⁻⁵ gives
#: MuJoCo's arms the same masses to 0.1 %; 0.1 leaves the UR5's wrist links +35 % and +49 %); not
#: zero, so that what the data never see of a payload stays at none.
PAYLOAD_PULL = 1e-3


@dataclass(frozen=True)
class ConsistentFit:
    """A physically consistent fit.

    Attributes:
        standard: (p,) standard parameters [kg, kg·m, kg·m²], 10 per body (pinocchio's order): φ, the
            payloads on their carriers (φ + P ψ: what is on each link).
        effects: (k,) effect coefficients θ, in the design's column order.
        base: (b,) base parameters K φ + R a (Eq. 2; the bodies and the rotors regrouped with them).
        rotors: (r,) rotor inertias a [kg·m²] of the joints ``rotor_joints`` (module docstring).
        rotor_joints: (r,) the joints whose rotors are held apart from the bodies.
        own_columns: (r,) bool, the rotors outside ``base``: a joint whose armature does not regroup
            with the bodies has a column of its own, a_j q̈_j on joint j's row (the model's effects lack
            it; :mod:`~excite_cli.identification.choice.consistent_model`); the others are in ``base``
            through R.
        bodies_base: (b,) the bodies' part of ``base``, K (φ + P ψ) (what a URDF of ``standard`` has).
        payloads: (l, 10) each payload's parameters ψ_l in its carrier's frame (module docstring).
        payload_bodies: (l,) the bodies that carry them.
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
    payloads: np.ndarray
    payload_bodies: list[str]
    own_columns: np.ndarray


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
    and each cross-validation fold's refit differ only in G, c and λ. The unknowns are
    u = column ⊙ [δ; a; θ] with φ + P ψ = φ_URDF + D δ (column: the design's column norms on all fit
    data), and the payloads ψ = D_P ω: a payload's columns are its carrier's, so the data term sees only
    their sum and keeps the size of a fit without payloads; ω enters the prior and the constraints.

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
        carriers: the bodies (0-based) that carry a payload of their own (module docstring; default
            none, :func:`~excite_cli.identification.fitting.bodies.last_bodies` gives the flanges).
    """

    def __init__(
        self,
        reference: np.ndarray,
        regrouping: np.ndarray,
        phi_urdf: np.ndarray,
        effect_names: list[str],
        bodies: list[str],
        rotors: dict[str, np.ndarray] | None = None,
        carriers: list[int] | None = None,
    ):
        phi_urdf = nearest_physical(phi_urdf)  # unseen parameters stay at φ_URDF: it must be feasible
        self.regrouping, self.phi_urdf, self.names, self.bodies = regrouping, phi_urdf, effect_names, bodies
        self.scale = scale = body_scales(phi_urdf)
        b, k, p = regrouping.shape[0], len(effect_names), scale.size
        self.rotor_joints, self.carriers = list(rotors or {}), list(carriers or [])
        self.rotors = np.column_stack([rotors[j] for j in self.rotor_joints]) if rotors else np.zeros((b, 0))
        self.first_effect = p + (r := len(self.rotor_joints))  # [δ; a] come before the effects θ
        self.nonnegative = np.array([name.split()[0] in NONNEGATIVE for name in effect_names], dtype=bool)
        # [Y_B K D, Y_B R, E]: the design in the unknowns [δ; a; θ]
        self.to_unknowns = np.zeros((b + k, p + r + k))
        self.to_unknowns[:b, :p] = regrouping * scale
        self.to_unknowns[:b, p : p + r] = self.rotors
        self.to_unknowns[b:, p + r :] = np.eye(k)
        column = np.sqrt(np.maximum(np.diag(self.to_unknowns.T @ reference @ self.to_unknowns), 0.0))
        self.unseen = column <= 1e-9 * column.max()
        column[self.unseen] = 1.0
        self.column = column
        self.placing = np.zeros((p, 10 * len(self.carriers)))  # P: each payload's ω onto its carrier's δ
        for n, body in enumerate(self.carriers):
            self.placing[10 * body : 10 * body + 10, 10 * n : 10 * n + 10] = np.eye(10)
        self.payload_scale = self.placing.T @ scale  # D_P: each payload scaled like its carrier, ψ = D_P ω
        size = p + r + k
        self.R, self.z = cp.Parameter((size, size)), cp.Parameter(size)  # the data term ‖R u − z‖², scaled by 1/M
        self.weight, self.pinned = cp.Parameter(nonneg=True), cp.Parameter(k, nonneg=True)
        self.u, self.omega = cp.Variable(size), cp.Variable(10 * len(self.carriers)) if self.carriers else None
        own = cp.multiply(self.u[:p], 1.0 / column[:p])  # the links' own D⁻¹(φ − φ_URDF)
        if self.carriers:
            own = own - self.placing @ self.omega
        prior = cp.sum_squares(own) + (PAYLOAD_PULL * cp.sum_squares(self.omega) if self.carriers else 0.0)
        objective = cp.sum_squares(self.R @ self.u - self.z) + self.weight * prior
        self.problem = cp.Problem(cp.Minimize(objective), self._constraints(own))

    def _constraints(self, own: cp.Expression) -> list:
        """Every body's own pseudo-inertia ⪰ ε_i (``own``: D⁻¹(φ − φ_URDF)), every payload's ⪰ 0, a ≥ 0,
        the non-negative effects, and the effects a fold's data never see pinned at 0."""
        u, scale, p = self.u, self.scale, self.scale.size
        phi = self.phi_urdf + cp.multiply(scale, own)
        # T J T ⪰ ε T² with T = diag(1/ℓ, 1/ℓ, 1/ℓ, 1)/√m₀: a congruence, same cone, entries of order 1
        T = np.diag([1.0 / LENGTH] * 3 + [1.0])
        out = [
            T @ pseudo_inertia_expression(phi[10 * i : 10 * i + 10]) @ T / scale[10 * i]
            >> MARGIN * np.diag([1.0] * 3 + [LENGTH**2])
            for i in range(len(self.bodies))
        ]
        for n, body in enumerate(self.carriers):
            psi = cp.multiply(self.payload_scale, self.omega)[10 * n : 10 * n + 10]
            out.append(T @ pseudo_inertia_expression(psi) @ T / scale[10 * body] >> 0)
        if self.rotor_joints:
            out.append(u[p : self.first_effect] >= 0)
        q = self.first_effect
        if self.nonnegative.any():
            out.append(u[q + np.flatnonzero(self.nonnegative)] >= 0)
        if self.names:  # an effect column a fold's data never see (a held-out run's offset) is kept at 0
            out.append(cp.multiply(self.pinned, u[q:]) == 0)
        return out

    def solve(self, G: np.ndarray, c: np.ndarray, rows: int, regularization: float) -> ConsistentFit:
        """The consistent fit to the weighted normal equations G (b + k, b + k), c (b + k,) of ``rows``
        rows, with regularization λ ≥ 0.

        Raises:
            ExciteError: the solver finds no solution (the message gives its status).
        """
        b, p, q, column = self.regrouping.shape[0], self.scale.size, self.first_effect, self.column
        normal = self.to_unknowns.T @ G @ self.to_unknowns / np.outer(column, column)
        right = self.to_unknowns.T @ (c - G[:, :b] @ (self.regrouping @ self.phi_urdf)) / column
        normal[self.unseen, :], normal[:, self.unseen] = 0.0, 0.0
        A, z = square_root(normal, right)
        R, padded = np.zeros_like(normal), np.zeros(normal.shape[0])  # RᵀR = the scaled normal matrix (padded)
        R[: len(A)], padded[: len(z)] = A, z
        self.R.value, self.z.value, self.weight.value = R / np.sqrt(rows), padded / np.sqrt(rows), regularization
        self.pinned.value = (np.diag(normal)[q:] <= 0.0).astype(float)
        problem = _solve(self.problem)
        unknowns = self.u.value / column
        standard = self.phi_urdf + self.scale * unknowns[:p]
        payloads = self.payload_scale * (self.omega.value if self.carriers else np.zeros(0))
        eigen = np.array([np.linalg.eigvalsh(pseudo_inertia(body))[0] for body in standard.reshape(-1, 10)])
        if np.any(eigen <= 0.0):
            raise ExciteError(
                "identification.fit",
                f"the SDP ended {problem.status} with a pseudo-inertia "
                f"that is not positive definite (body {self.bodies[int(np.argmin(eigen))]})",
            )
        rotors, coefficients = unknowns[p:q], unknowns[q:]
        bodies = self.regrouping @ standard
        return ConsistentFit(
            standard,
            coefficients,
            bodies + self.rotors @ rotors,
            eigen,
            self._active(eigen, coefficients, rotors),
            str(problem.status),
            self._unconstrained(R / np.sqrt(rows), padded / np.sqrt(rows), regularization),
            rotors,
            self.rotor_joints,
            bodies,
            payloads.reshape(-1, 10),
            [self.bodies[i] for i in self.carriers],
            np.zeros(len(self.rotor_joints), dtype=bool),
        )

    def _unconstrained(self, R: np.ndarray, z: np.ndarray, regularization: float) -> np.ndarray:
        """(p,) φ + P ψ of the same problem without the constraints (regularized least squares). For a
        given carrier's δ the best ω is δ/(1 + μ), which leaves the prior μ/(1 + μ) ‖δ‖² on it."""
        p, column = self.scale.size, self.column
        pull = np.where(self.placing.any(axis=1), PAYLOAD_PULL / (1.0 + PAYLOAD_PULL), 1.0)
        prior = np.zeros((p, column.size))
        prior[:, :p] = np.diag(np.sqrt(regularization * pull) / column[:p])
        plain = np.linalg.lstsq(np.vstack([R, prior]), np.concatenate([z, np.zeros(p)]), rcond=None)[0]
        return self.phi_urdf + self.scale * plain[:p] / column[:p]

    def _active(self, eigen: np.ndarray, coefficients: np.ndarray, rotors: np.ndarray) -> list[str]:
        """The constraints at their bound, in words."""
        epsilon = MARGIN * self.scale[0::10] * LENGTH**2
        out = [f"pseudo-inertia of {name}" for name, e, eps in zip(self.bodies, eigen, epsilon) if e <= ACTIVE * eps]
        out += [f"{self.names[c]} ≥ 0" for c in np.flatnonzero(self.nonnegative & (coefficients <= 1e-9))]
        return out + [f"rotor of {j} ≥ 0" for j, a in zip(self.rotor_joints, rotors) if a <= 1e-9]
