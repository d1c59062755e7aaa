"""Centre-of-mass region for balance (Eq. 52): the ground projection of the centre of total mass,
computed from the a-priori (URDF) inertias with the base held fixed, stays in a region around the
centre of the support area: a disc of radius r (the paper: 1 cm) or a convex polygon.

Disc: s_t = (‖p_t − c‖² / r² − 1) / 2. Polygon with outward unit normals n_k and distances b_k from
the centre to its edges: s_t,k = (n_kᵀ(p_t − c) − b_k) / b_min. Both are ≤ 0 inside, aggregated by
a log-sum-exp over the constraint grid; the gradient comes from pinocchio's CoM Jacobian.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from excite_cli.config import ComConfig
from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.constraints.lse import ACCEPT_MARGIN, smooth_max
from excite_cli.constraints.support import support_polygon
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.trajectory.fourier import FourierBasis

#: Points of the support links within this height of their lowest point form the soles [m].
SOLE_HEIGHT = 0.005


def support_centre(robot: Robot, links: list[str]) -> np.ndarray:
    """Centre (x, y) [m] of the support area: the area centroid of the convex hull of the soles,
    i.e. the collision-geometry points of ``links`` within ``SOLE_HEIGHT`` of their lowest height, at
    the home posture (:func:`~excite_cli.constraints.support.support_polygon`).

    Raises:
        ExciteError: a link without collision geometry, or soles spanning no area.
    """
    return support_polygon(robot, links, SOLE_HEIGHT, "constraints.com.support_links").centroid


class ComRegion(Constraint):
    """Eq. 52 on the constraint grid, one aggregated inequality.

    Args:
        robot: the robot (CoM and its Jacobian).
        basis: Fourier basis on the constraint grid.
        centre: (2,) centre c of the region [m], world x, y.
        radius: disc radius [m], or None with ``polygon``.
        polygon: (K, 2) convex polygon vertices relative to c [m], or None with ``radius``.

    Raises:
        ExciteError: a polygon that is not convex or does not contain the centre.
    """

    name = "com_region"
    field = "constraints.com"
    grid_margin = ACCEPT_MARGIN

    def __init__(
        self,
        robot: Robot,
        basis: FourierBasis,
        centre: np.ndarray,
        radius: float | None = None,
        polygon: np.ndarray | None = None,
    ):
        self.robot, self.basis, self.centre = robot, basis, np.asarray(centre, dtype=float)
        self._data = robot.model.createData()  # this constraint's own pinocchio Data
        self.radius = radius
        self.polygon = None if polygon is None else np.asarray(polygon, dtype=float)
        if polygon is not None:
            v = np.asarray(polygon, dtype=float)
            if np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]) < 0:
                v = v[::-1]  # counter-clockwise
            edge = np.roll(v, -1, axis=0) - v
            normals = np.stack([edge[:, 1], -edge[:, 0]], axis=1) / np.linalg.norm(edge, axis=1)[:, None]
            offsets = np.einsum("kx,kx->k", normals, v)
            turn = edge[:, 0] * np.roll(edge[:, 1], -1) - edge[:, 1] * np.roll(edge[:, 0], -1)
            if np.any(offsets <= 0) or np.any(turn < 0):
                raise ExciteError("constraints.com.polygon", "must be convex and contain the support centre")
            self.normals, self.offsets = normals, offsets

    def _com(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(T, 2) ground projections [m] and (T, 2, n) their Jacobians."""
        r, data = self.robot, self._data
        configurations = r.states(Q, np.zeros_like(Q), np.zeros_like(Q))[0]
        P, J = np.empty((len(Q), 3)), np.empty((len(Q), 3, r.model.nv))
        for t, q in enumerate(configurations):  # Robot.com's pinocchio calls, without its per-call set-up
            J[t] = pin.jacobianCenterOfMass(r.model, data, q, False)
            P[t] = data.com[0]
        return P[:, :2], J[:, :2, r.v_idx]

    def _normalized(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """s (T, K) and ∂s/∂p (T, K, 2)."""
        d = P - self.centre
        if self.radius is not None:
            s = (np.einsum("tx,tx->t", d, d) / self.radius**2 - 1.0) / 2.0
            return s[:, None], (d / self.radius**2)[:, None, :]
        scale = self.offsets.min()
        s = (d @ self.normals.T - self.offsets) / scale
        return s, np.broadcast_to(self.normals / scale, (len(P),) + self.normals.shape)

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One aggregated value (1,) and its Jacobian (1, α.size), see :meth:`Constraint.evaluate`."""
        P, J = self._com(self.basis.q @ alpha.T)
        s, ds = self._normalized(P)
        g, w = smooth_max(s, axis=(0, 1))
        dq = np.einsum("tk,tkx,txn->tn", w, ds, J)
        return np.atleast_1d(g), (dq.T @ self.basis.q).reshape(1, -1)

    track_units = {"com_xy": "m"}

    def drawn(self) -> dict[str, object]:
        """The region around the CoM's track: its centre, and its radius or polygon."""
        return {"centre": self.centre, "radius": self.radius, "polygon": self.polygon}

    def track(self, alpha: np.ndarray, basis: FourierBasis) -> dict[str, np.ndarray]:
        """``com_xy``: (T, 2) ground projection of the CoM [m]."""
        return {"com_xy": self._com(basis.q @ alpha.T)[0]}

    def check_samples(self, time: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> FineCheck:
        """Largest CoM excursion from the centre [m] and the normalized violation at the postures q (T, n)."""
        P, _ = self._com(q)
        s, _ = self._normalized(P)
        excursion = float(np.linalg.norm(P - self.centre, axis=1).max())
        if self.radius is not None:
            violation_m = excursion - self.radius
        else:
            violation_m = float(((P - self.centre) @ self.normals.T - self.offsets).max())
        return FineCheck(
            max_violation=float(s.max()),
            details={"com_max_excursion_m": excursion, "com_max_violation_m": violation_m},
            where=f"CoM {excursion * 100:.2f} cm from the support centre",
        )


def com_region_from_config(cfg: ComConfig, robot: Robot, basis: FourierBasis) -> ComRegion:
    """The :class:`ComRegion` of ``constraints.com`` (support centre from the soles or given)."""
    centre = np.asarray(cfg.centre) if cfg.centre is not None else support_centre(robot, cfg.support_links)
    return ComRegion(robot, basis, centre, cfg.radius, None if cfg.polygon is None else np.asarray(cfg.polygon))
