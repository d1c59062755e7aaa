"""One body's inertial parameters: its pseudo-inertia (the matrix that is positive definite exactly
when some mass distribution has the parameters), its mass, centre of mass and principal moments, the
nearest physical body to one that is not, the prior's scale of its parameters, and the bodies at the
end of the robot's chains (where a tool or payload is carried).

Per body, with pinocchio's parameters φ_i = [m, h_x, h_y, h_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz]
(h = m c, I the rotational inertia about the body frame's origin), the pseudo-inertia is

    J_i = [[Σ, h], [hᵀ, m]],  Σ = ½ tr(I) 𝟙 − I  (the second moment ∫ x xᵀ dm),

and J_i ≻ 0 is exactly "some positive mass distribution has these parameters": m > 0, I_c ≻ 0 and
the triangle inequalities of its principal moments (Wensing, Kim, Slotine, "Linear matrix inequalities
for physically consistent inertial parameter identification", RA-L 2017).
"""

from __future__ import annotations

import cvxpy as cp
import numpy as np
import pinocchio as pin

#: Length scale ℓ [m] of the inertia parameters in the regularization.
LENGTH = 0.1
#: ε_i = this × m₀ ℓ²: the smallest eigenvalue kept by each pseudo-inertia [kg·m²].
MARGIN = 1e-5


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


def pseudo_inertia_expression(phi) -> cp.Expression:
    """The same as :func:`pseudo_inertia` for a cvxpy vector of 10 (affine in φ)."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = (phi[k] for k in range(10))
    half = 0.5 * (ixx + iyy + izz)
    return cp.bmat(
        [[half - ixx, -ixy, -ixz, hx], [-ixy, half - iyy, -iyz, hy], [-ixz, -iyz, half - izz, hz], [hx, hy, hz, m]]
    )


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


def last_bodies(model: pin.Model) -> list[int]:
    """The bodies (0-based: body i is carried by joint i + 1) that carry no other body: a serial arm's
    last link, each arm's hand of a humanoid."""
    parents = set(model.parents[1:])
    return [j - 1 for j in range(1, model.njoints) if j not in parents]
