"""Closest points of segment pairs, and the capsule-pair distances of the self-collision constraint
aggregated over the constraint grid, in compiled loops (numba).

The closest points of two segments p1 + s·d1 and p2 + t·d2 (s, t in [0, 1]) are Ericson's closed
form (Real-Time Collision Detection, 2005, Sec. 5.1.9, degenerate (point) segments included); a
capsule pair's distance is |c₂ − c₁| − r₁ − r₂ with unit normal n = (c₂ − c₁)/|c₂ − c₁|.

Why compiled: the self-collision constraint asks for every capsule pair at every grid instant (the
G1 arms: 179 pairs × 401 instants) at each trial point of the solver. Vectorized numpy spent most of
an optimizer iteration on the temporaries of this closed form (about 30 array passes of 72 000
elements, then the log-sum-exp and the weights over them); one loop over (pair, instant) keeps each
value in registers. Neither pinocchio nor coal offers segment distances in batches (coal answers one
pair per Python call, about 100 times slower here); coal stays the reference of the exact checks.

Compiled without fast-math: every operation is IEEE double in source order, with no fused
multiply-add and no reordered sums, so a kernel gives the same bits on every x86-64 processor, as
NumPy and OpenBLAS do under :mod:`excite_cli.kernels`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

#: Segments shorter than this (squared length [m²]) are points; a smaller denominator means parallel.
TINY = 1e-12
#: Instants whose log-sum-exp weight is below this add nothing to a pair's Jacobian that double
#: precision keeps (their sum over a grid stays below 1e-13 of the largest weight's part).
WEIGHT_FLOOR = 1e-16


class CapsulePairs(NamedTuple):
    """The capsule pairs the loops below take, in the order of their compiled kernels' arguments.

    Attributes:
        first, second: (P,) int, the capsule indices of each pair.
        radii: (C,) every capsule's radius [m].
        margins: (P,) each pair's required clearance [m].
        scale: L [m], the distances' normalization (s = (margin − d)/L).
        sharpness: β of the log-sum-exp over the instants.
    """

    first: np.ndarray
    second: np.ndarray
    radii: np.ndarray
    margins: np.ndarray
    scale: float
    sharpness: float


@njit(cache=True, inline="always")
def _clip01(x: float) -> float:
    return min(max(x, 0.0), 1.0)


@njit(cache=True, inline="always")
def _parameters(rx, ry, rz, d1x, d1y, d1z, d2x, d2y, d2z):
    """(s, t) of the closest points of p1 + s·d1 and p2 + t·d2, from r = p1 − p2 (Ericson 5.1.9)."""
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    if a <= TINY and e <= TINY:
        return 0.0, 0.0
    if a <= TINY:
        return 0.0, _clip01(f / e)
    c = d1x * rx + d1y * ry + d1z * rz
    if e <= TINY:
        return _clip01(-c / a), 0.0
    b = d1x * d2x + d1y * d2y + d1z * d2z
    denom = a * e - b * b
    s = _clip01((b * f - c * e) / denom) if denom > TINY else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        return _clip01(-c / a), 0.0
    if t > 1.0:
        return _clip01((b - c) / a), 1.0
    return s, t


@njit(cache=True, inline="always")
def _pair(start, end, t, i, j):
    """Closest point c₁ on capsule i's segment, the gap c₂ − c₁ to capsule j's and its length, at
    instant t of segment ends (3, T, C)."""
    p1x, p1y, p1z = start[0, t, i], start[1, t, i], start[2, t, i]
    p2x, p2y, p2z = start[0, t, j], start[1, t, j], start[2, t, j]
    d1x, d1y, d1z = end[0, t, i] - p1x, end[1, t, i] - p1y, end[2, t, i] - p1z
    d2x, d2y, d2z = end[0, t, j] - p2x, end[1, t, j] - p2y, end[2, t, j] - p2z
    s, u = _parameters(p1x - p2x, p1y - p2y, p1z - p2z, d1x, d1y, d1z, d2x, d2y, d2z)
    cx, cy, cz = p1x + s * d1x, p1y + s * d1y, p1z + s * d1z
    gx, gy, gz = (p2x + u * d2x) - cx, (p2y + u * d2y) - cy, (p2z + u * d2z) - cz
    return cx, cy, cz, gx, gy, gz, np.sqrt(gx * gx + gy * gy + gz * gz)


@njit(cache=True)
def _closest_points(p1, q1, p2, q2, c1, c2):
    for k in range(p1.shape[1]):
        d1x, d1y, d1z = q1[0, k] - p1[0, k], q1[1, k] - p1[1, k], q1[2, k] - p1[2, k]
        d2x, d2y, d2z = q2[0, k] - p2[0, k], q2[1, k] - p2[1, k], q2[2, k] - p2[2, k]
        r = (p1[0, k] - p2[0, k], p1[1, k] - p2[1, k], p1[2, k] - p2[2, k])
        s, t = _parameters(r[0], r[1], r[2], d1x, d1y, d1z, d2x, d2y, d2z)
        c1[0, k], c1[1, k], c1[2, k] = p1[0, k] + s * d1x, p1[1, k] + s * d1y, p1[2, k] + s * d1z
        c2[0, k], c2[1, k], c2[2, k] = p2[0, k] + t * d2x, p2[1, k] + t * d2y, p2[2, k] + t * d2z


def segment_closest_points(
    p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Closest points c1 on segment [p1, q1] and c2 on [p2, q2] [m]: every array has its coordinates
    on the first axis, (3, ...), the rest broadcast together; c1 and c2 have the broadcast shape.

    Ericson, Real-Time Collision Detection, 2005, Sec. 5.1.9 (degenerate segments: points)."""
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (p1, q1, p2, q2)))
    shape = arrays[0].shape
    flat = [np.ascontiguousarray(x.reshape(3, -1)) for x in arrays]
    c1, c2 = np.empty_like(flat[0]), np.empty_like(flat[0])
    _closest_points(*flat, c1, c2)
    return c1.reshape(shape), c2.reshape(shape)


@njit(cache=True)
def _pair_distances(start, end, first, second, radii, d):
    for k in range(first.shape[0]):
        i, j = first[k], second[k]
        for t in range(start.shape[1]):
            d[t, k] = _pair(start, end, t, i, j)[6] - radii[i] - radii[j]


def pair_distances(start: np.ndarray, end: np.ndarray, pairs: CapsulePairs) -> np.ndarray:
    """Distances d (T, P) [m] of the capsule ``pairs`` (P pairs) from their segments' world ends
    start, end (3, T, C) [m]."""
    d = np.empty((start.shape[1], pairs.first.size))
    _pair_distances(start, end, pairs.first, pairs.second, pairs.radii, d)
    return d


@njit(cache=True, inline="always")
def _exponents(start, end, i, j, radii, margin, scale, sharpness, out):
    """β(margin − d_t)/L of one pair at every instant into ``out`` (T,); returns their largest."""
    peak = -np.inf
    for t in range(start.shape[1]):
        length = _pair(start, end, t, i, j)[6]
        out[t] = sharpness * ((margin - (length - radii[i] - radii[j])) / scale)
        peak = max(peak, out[t])
    return peak


@njit(cache=True, inline="always")
def _total(exponents, peak):
    total = 0.0
    for t in range(exponents.size):
        total += np.exp(exponents[t] - peak)
    return total


@njit(cache=True)
def _pair_aggregates(start, end, first, second, radii, margins, scale, sharpness, g):
    exponents = np.empty(start.shape[1])
    for k in range(first.shape[0]):
        peak = _exponents(start, end, first[k], second[k], radii, margins[k], scale, sharpness, exponents)
        g[k] = (peak + np.log(_total(exponents, peak))) / sharpness


def pair_aggregates(start: np.ndarray, end: np.ndarray, pairs: CapsulePairs) -> np.ndarray:
    """Per pair k, the log-sum-exp over the instants t of s_t = (margins[k] − d_t)/scale:
    g_k = (1/β) log Σ_t exp(β s_t) (P,), β = ``pairs.sharpness``, stable (shifted by the largest term).

    Args:
        start, end: (3, T, C) the capsules' segment ends in the world [m].
        pairs: the P pairs, their margins, L and β.
    """
    g = np.empty(pairs.first.size)
    _pair_aggregates(start, end, *pairs, g)
    return g


@njit(cache=True)
def _pair_jacobian(
    start, end, first, second, radii, margins, scale, sharpness, axes, moments, revolute, moves, basis, g, J
):
    T, n, m = start.shape[1], moves.shape[1], basis.shape[1]
    exponents = np.empty(T)
    for k in range(first.shape[0]):
        i, j = first[k], second[k]
        peak = _exponents(start, end, i, j, radii, margins[k], scale, sharpness, exponents)
        total = _total(exponents, peak)
        g[k] = (peak + np.log(total)) / sharpness
        for t in range(T):
            weight = np.exp(exponents[t] - peak) / total
            if weight < WEIGHT_FLOOR:
                continue
            cx, cy, cz, gx, gy, gz, length = _pair(start, end, t, i, j)
            inv = -weight / scale / max(length, 1e-12)  # ∂g/∂d folded into the normal
            nx, ny, nz = gx * inv, gy * inv, gz * inv
            mx, my, mz = cy * nz - cz * ny, cz * nx - cx * nz, cx * ny - cy * nx  # c₁ × n
            for q in range(n):
                if moves[k, q] == 0.0:
                    continue
                ax, ay, az = axes[t, 0, q], axes[t, 1, q], axes[t, 2, q]
                if revolute[q]:
                    turn = nx * moments[t, 0, q] + ny * moments[t, 1, q] + nz * moments[t, 2, q]
                    rate = mx * ax + my * ay + mz * az - turn
                else:
                    rate = nx * ax + ny * ay + nz * az
                rate *= moves[k, q]
                for c in range(m):
                    J[k, q, c] += rate * basis[t, c]


def pair_jacobian(
    start: np.ndarray,
    end: np.ndarray,
    pairs: CapsulePairs,
    axes: np.ndarray,
    moments: np.ndarray,
    revolute: np.ndarray,
    moves: np.ndarray,
    basis: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The aggregates g (P,) of :func:`pair_aggregates` and their Jacobian (P, n, m) in the Fourier
    coefficients α (n, m) of the active joints.

    ∂g_k/∂α_q = Σ_t w_t (∂s_t/∂d_t) ∂d_t/∂q_q(t) B(t), with the log-sum-exp weights w_t (those below
    ``WEIGHT_FLOOR`` skipped), ∂s/∂d = −1/L and ∂d/∂q_q = ±nᵀ(a_q × (c₁ − o_q)) = ±((c₁ × n)·a_q −
    n·(a_q × o_q)) for a revolute joint (nᵀa_q prismatic): the velocity Jacobian of the closest point,
    as if fixed to a body below every joint, projected on the normal (either closest point gives the
    same, since c₂ × n = c₁ × n), the sign ``moves[k, q]`` (+1: the joint moves only the second
    capsule, −1 only the first, 0 both or neither; Eq. 53's gradient from the witness points).

    Args:
        start, end, pairs: as :func:`pair_aggregates`.
        axes, moments: (T, 3, n) each active joint's world axis a_q and a_q × o_q at every instant
            (:meth:`~excite_cli.dynamics.kinematics.BatchKinematics.joint_axes`); revolute: (n,) bool.
        moves: (P, n) the signs above; basis: (T, m) the Fourier basis of q at the instants.
    """
    P, n, m = pairs.first.size, moves.shape[1], basis.shape[1]
    g, J = np.empty(P), np.zeros((P, n, m))
    _pair_jacobian(start, end, *pairs, axes, moments, revolute, moves, basis, g, J)
    return g, J
