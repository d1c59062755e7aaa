"""Balance under acceleration: the zero-moment point (ZMP) of a robot standing on flat feet stays inside
its support polygon shrunk by a margin, and the ground pushes up.

With the feet fixed to the ground, the ground supplies the wrench that the floating base's first six
rows of inverse dynamics ask for with the base at rest (RNEA with v_base = a_base = 0): a force f and
a moment n_O about the world origin, in the world frame (the base is held at the identity). The ZMP
on the ground plane z = h is where the horizontal moment of that wrench vanishes (Kajita et al.,
*Introduction to Humanoid Robotics*, 2014, ch. 3; Sardain & Bessonnet, IEEE T-SMC 2004):

    p_x = (h f_x − n_O,y) / f_z,    p_y = (h f_y + n_O,x) / f_z,

equal to the centre of pressure while both feet are flat. Unlike the centre-of-mass region (Eq. 52)
it moves with the arms' accelerations, which is what tips a standing humanoid. Per instant t and
polygon edge k (outward normal n_k, offset b_k), s_t,k = (n_kᵀp_t − b_k + margin) / L, aggregated by
a log-sum-exp over the grid into one inequality, and s_t = −f_z,t / (0.1 m g) into another (F_z > 0).

The Jacobian in α comes from pinocchio's RNEA derivatives (Carpentier & Mansard 2018), their base
rows: with q_j(t) = B(t) α_j (Eq. 50), ∂w_t/∂α_j = ∂w/∂q_j B(t) + ∂w/∂q̇_j Ḃ(t) + M_bj B̈(t), at the
instants whose aggregation weight is not negligible.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from excite_cli.config import ZmpConfig
from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.constraints.lse import ACCEPT_MARGIN, smooth_max, smooth_max_value
from excite_cli.constraints.self_collision import LENGTH_SCALE
from excite_cli.constraints.support import SupportPolygon, soles_on_an_edge, support_polygon, tilted_stance
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.memo import once
from excite_cli.trajectory.fourier import FourierBasis

#: The soles' contact points: collision points within this height of the lowest [m] (a sphere's
#: bottom, a box's lower face), the polygon the centre of pressure can reach.
CONTACT_HEIGHT = 0.001
#: What a drafted home posture keeps beyond the margin [m] (or a third of the room beyond it on small soles).
HOME_CLEARANCE = 0.02
#: Standard gravity [m/s²], which pinocchio's models carry.
GRAVITY = 9.81
#: The normal force's row is normalized by this fraction of the weight m g: −F_z / (0.1 m g) ≤ 0, so
#: that its aggregation weights gather on the few instants of least F_z, as the edges' do.
FORCE_SCALE = 0.1
#: Instants whose aggregation weights are all below this get no RNEA derivatives (their share of the
#: Jacobian is below rounding).
NEGLIGIBLE_WEIGHT = 1e-16


def has_floating_base(robot: Robot) -> bool:
    """Whether the robot's model starts with a free-flyer joint (``robot.floating_base: true``)."""
    return robot.model.njoints > 1 and robot.model.joints[1].shortname() == "JointModelFreeFlyer"


def zero_moment_point(wrench: np.ndarray, height: float) -> np.ndarray:
    """(T, 2) ZMP [m] on the plane z = ``height`` [m] of ground wrenches ``wrench`` (T, 6): force
    f [N] then moment n_O [N·m] about the world origin, in the world frame (Kajita et al. 2014, ch. 3)."""
    f, n = wrench[:, :3], wrench[:, 3:]
    return np.stack([height * f[:, 0] - n[:, 1], height * f[:, 1] + n[:, 0]], axis=1) / f[:, 2:3]


class ZeroMomentPoint(Constraint):
    """The ZMP inside the support polygon shrunk by ``margin`` and F_z > 0, on the constraint grid:
    two aggregated inequalities.

    Args:
        robot: a floating-base robot (its URDF inertias give the ground wrench).
        basis: Fourier basis on the constraint grid.
        polygon: the support polygon and the ground plane.
        margin: distance [m] the ZMP keeps from every edge.

    Raises:
        ExciteError: a robot without a floating base; a margin that leaves no polygon.
    """

    name = "zmp"
    field = "constraints.zmp"
    grid_margin = ACCEPT_MARGIN
    track_units = {"zmp_xy": "m"}
    advisory = True
    eased_by_slowing = True

    def __init__(self, robot: Robot, basis: FourierBasis, polygon: SupportPolygon, margin: float):
        if not has_floating_base(robot):
            raise ExciteError(
                "constraints.zmp", "needs robot.floating_base: true (the ground wrench is the floating base's)"
            )
        room = float(polygon.margins(polygon.centroid[None])[0])
        if margin >= room:
            raise ExciteError(
                "constraints.zmp.margin",
                f"{margin:g} m leaves no support polygon (its centre is {room:.3g} m from the nearest edge)",
                margin,
                f"less than {room:.3g} m",
            )
        self.robot, self.basis, self.polygon, self.margin = robot, basis, polygon, float(margin)
        # a drafted home keeps 2 cm beyond the margin (a third of the room there is on small soles: iCub's
        # locked legs leave its arms' home at most 4 mm beyond its 20 mm margin): the arms' accelerations move
        # the ZMP from where it stands
        self.home_clearance = min(HOME_CLEARANCE, (room - self.margin) / 3)
        self.data = robot.model.createData()
        self._orders = (basis.q, basis.qd, basis.qdd)
        self._weight = GRAVITY * sum(inertia.mass for inertia in robot.model.inertias)

    def in_words(self) -> str:
        """The rows, in words (for ``check``)."""
        home = self.check_samples(np.zeros(1), self.robot.home[None], *np.zeros((2, 1, self.robot.n_joints)))
        return (
            f"ZMP inside the support polygon less {1000 * self.margin:g} mm "
            f"(standing at home: {1000 * float(home.details['zmp_min_margin_m']):.1f} mm inside); F_z > 0"
        )

    def clearance(self, Q: np.ndarray) -> np.ndarray:
        """(K,) the distance [m] beyond the margin of the ZMP of the robot standing still at each posture
        Q (K, n) [rad] (there, the centre of mass's ground projection)."""
        still = np.zeros_like(Q)
        return (
            self.polygon.margins(zero_moment_point(self.wrenches(Q, still, still), self.polygon.height)) - self.margin
        )

    def ground_point(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """(S, 2) the zero-moment point [m], world x, y, at the samples q, q̇, q̈ (S, n) (Kajita et al. 2014, ch. 3)."""
        return zero_moment_point(self.wrenches(q, qd, qdd), self.polygon.height)

    def wrenches(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """(T, 6) ground wrench [N, N·m] (force, moment about the world origin, world frame) at the
        samples q, q̇, q̈ (T, n) of the active joints, base at rest."""
        return self._wrenches(self.robot.states(q, qd, qdd))

    def _wrenches(self, states: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
        """(T, 6) ground wrench of the full model's states (:meth:`Robot.states`): RNEA's base rows."""
        r = self.robot
        return np.array([pin.rnea(r.model, self.data, *state)[:6] for state in zip(*states)])

    def _normalized(self, wrench: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The ZMP (T, 2) [m], s of the edges (T, K) and s of the normal force (T,), normalized."""
        p = zero_moment_point(wrench, self.polygon.height)
        edges = (p @ self.polygon.normals.T - self.polygon.offsets + self.margin) / LENGTH_SCALE
        return p, edges, -wrench[:, 2] / (FORCE_SCALE * self._weight)

    def _on_grid(self, alpha: np.ndarray) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
        """The full model's states on the grid (:meth:`Robot.states`) and the ground wrench (T, 6) of α,
        kept for the next call at the same α (a solver asks for the values at a trial point, then the
        Jacobian at the one it accepts)."""

        def compute():
            states = self.robot.states(*(B @ alpha.T for B in self._orders))
            return states, self._wrenches(states)

        return once(self, "grid", alpha, compute)

    def values(self, alpha: np.ndarray) -> np.ndarray:
        """The two values of :meth:`evaluate` from RNEA alone, without the derivatives."""
        _, edges, force = self._normalized(self._on_grid(alpha)[1])
        return np.array([smooth_max_value(edges, (0, 1)), smooth_max_value(force, 0)])

    def evaluate(self, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The two aggregated values (ZMP, normal force) and their Jacobian (2, α.size)."""
        r, d = self.robot, self.data
        states, wrench = self._on_grid(alpha)
        p, edges, force = self._normalized(wrench)
        g_edges, w_edges = smooth_max(edges, (0, 1))
        g_force, w_force = smooth_max(force, 0)
        fz, h, T = wrench[:, 2], self.polygon.height, len(wrench)
        dp = np.zeros((T, 2, 6))  # ∂p/∂w: p_x = (h f_x − n_y)/f_z, p_y = (h f_y + n_x)/f_z
        dp[:, 0, 0], dp[:, 0, 4], dp[:, 0, 2] = h / fz, -1.0 / fz, -p[:, 0] / fz
        dp[:, 1, 1], dp[:, 1, 3], dp[:, 1, 2] = h / fz, 1.0 / fz, -p[:, 1] / fz
        dg = np.zeros((2, T, 6))  # ∂g/∂w_t of both rows
        dg[0] = np.einsum("tk,kx,txw->tw", w_edges, self.polygon.normals / LENGTH_SCALE, dp)
        dg[1, :, 2] = -w_force / (FORCE_SCALE * self._weight)
        instants = np.flatnonzero(np.abs(dg).max(axis=(0, 2)) > NEGLIGIBLE_WEIGHT)
        rows = np.empty((3, instants.size, 6, r.model.nv))  # ∂w/∂q, ∂w/∂q̇ and M's base rows
        for i, t in enumerate(instants):
            pin.computeRNEADerivatives(r.model, d, states[0][t], states[1][t], states[2][t])
            rows[0, i], rows[1, i], rows[2, i] = d.dtau_dq[:6], d.dtau_dv[:6], d.M[:6]  # M: its upper triangle
        jacobian = sum(  # the active joints' columns
            np.einsum("rtw,twj->rjt", dg[:, instants], D[..., r.v_idx]) @ B[instants]
            for D, B in zip(rows, self._orders)
        )
        return np.array([g_edges, g_force]), jacobian.reshape(2, -1)

    def check_samples(self, time: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> FineCheck:
        """The smallest distance [m] of the ZMP inside the support polygon, when and where it is, the
        smallest normal force as a fraction of the weight, and the normalized violation."""
        wrench = self.wrenches(q, qd, qdd)
        p, _, force = self._normalized(wrench)
        inside = self.polygon.margins(p)
        t = int(np.argmin(inside))
        violation = max(float((self.margin - inside.min()) / LENGTH_SCALE), float(force.max()))
        return FineCheck(
            max_violation=violation,
            details={
                "zmp_min_margin_m": float(inside[t]),
                "zmp_min_margin_time_s": float(time[t]),
                "zmp_min_normal_force_ratio": float(-force.max() * FORCE_SCALE),
            },
            where=(
                f"ZMP {1000 * inside[t]:.1f} mm inside the support polygon at t = {time[t]:.2f} s "
                f"(x {p[t, 0]:.3f}, y {p[t, 1]:.3f} m)"
            ),
        )

    def drawn(self) -> dict[str, object]:
        """The support polygon around the ZMP's track, less its margin."""
        return {"support": self.polygon, "zmp_margin": self.margin}

    def track(self, alpha: np.ndarray, basis: FourierBasis) -> dict[str, np.ndarray]:
        """``zmp_xy``: (T, 2) the ZMP on the ground plane [m] on ``basis``'s instants."""
        return {"zmp_xy": zero_moment_point(self.wrenches(*basis.evaluate(alpha)), self.polygon.height)}


def zmp_from_config(cfg: ZmpConfig, robot: Robot, basis: FourierBasis) -> ZeroMomentPoint:
    """The :class:`ZeroMomentPoint` of ``constraints.zmp`` (support polygon from the soles' contact points).

    Raises:
        ExciteError: see :class:`ZeroMomentPoint` and :func:`~excite_cli.constraints.support.support_polygon`;
            a margin that leaves no polygon because soles stand on an edge is the held joints' fault
            (:func:`~excite_cli.constraints.support.tilted_stance`).
    """
    field = "constraints.zmp.support_links"
    polygon = support_polygon(robot, cfg.support_links, CONTACT_HEIGHT, field)
    try:
        return ZeroMomentPoint(robot, basis, polygon, cfg.margin)
    except ExciteError as error:
        margin_failed = error.field == "constraints.zmp.margin"
        edges = soles_on_an_edge(robot, cfg.support_links, CONTACT_HEIGHT, field) if margin_failed else []
        if edges:
            raise tilted_stance(edges, f"constraints.zmp.margin {cfg.margin:g} m leaves no support polygon") from None
        raise
