"""The export played on MuJoCo's robot by the lab's controller, and what MuJoCo measured.

Each controller tick holds one sample of the export (zero-order hold) for 1 / rate: the active joints'
PD set point and feed-forward torque, a standing robot's held joints' set point and their feed-forward.
The centre of pressure comes from the floor's contact forces (``mj_contactForce``), the support polygon
from MuJoCo's contact points standing still (MuJoCo documentation: Computation, Contact; Programming,
Simulation).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from excite_cli.constraints.support import SupportPolygon
from excite_cli.identification.reporting.mjcf_out import import_mujoco
from excite_cli.rehearsal.mujoco_robot import RehearsalRobot, pose

#: Seconds standing still at the first sample before the motion starts.
SETTLE = 2.0
#: A robot whose root drops more than this below its standing height has fallen [m] ...
FALL_DROP = 0.05
#: ... or a sole tilted more than this from its standing orientation [deg] (a foot on its edge) ...
FALL_SOLE_TILT = 5.0
#: ... or its root more than this [deg].
FALL_ROOT_TILT = 20.0


@dataclass(frozen=True)
class Commands:
    """What the controller sends at each tick.

    Attributes:
        q, qd, tau: (S, n) the active joints' set points [rad], velocities [rad/s] and feed-forward [N·m].
        held_tau: (S, h) the held joints' feed-forward [N·m] (in ``RehearsalRobot.held``'s order), or None.
        rate: ticks per second [Hz].
    """

    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    held_tau: np.ndarray | None
    rate: float


@dataclass(frozen=True)
class Played:
    """What MuJoCo measured at each tick.

    Attributes:
        time: (S,) [s] from the start of the motion.
        q, qd: (S, n) the active joints' measured positions [rad] and velocities [rad/s].
        tau: (S, n) the torques the active joints' actuators applied (feed-forward + PD) [N·m].
        held_tau: (S, h) the held joints' applied torques [N·m] (h = 0 for a fixed base).
        contacts: {(body, body): first time [s]} of the contacts that were not there at rest.
        at_rest: (body, body) pairs already touching at the first sample, not counted.
        cop: (S, 2) centre of pressure [m], world x, y (NaN while no sole touches; standing only).
        com: (S, 2) centre of mass [m], world x, y (standing only).
        polygon: the support polygon of MuJoCo's contact points standing still (standing only).
        sole_tilt, root_tilt: (S,) the largest sole's and the root's tilt from standing [deg].
        drop: (S,) how far the root is below its standing height [m].
    """

    time: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    held_tau: np.ndarray
    contacts: dict[tuple[str, str], float]
    at_rest: tuple[tuple[str, str], ...]
    cop: np.ndarray | None = None
    com: np.ndarray | None = None
    polygon: SupportPolygon | None = None
    sole_tilt: np.ndarray | None = None
    root_tilt: np.ndarray | None = None
    drop: np.ndarray | None = None

    @property
    def margin(self) -> np.ndarray:
        """(S,) the centre of pressure's distance inside the support polygon [m] (−inf with no contact)."""
        inside = self.polygon.margins(np.nan_to_num(self.cop, nan=np.inf))
        return np.where(np.isnan(self.cop).any(axis=1), -np.inf, inside)

    @property
    def fell(self) -> bool:
        """Whether the root dropped more than ``FALL_DROP`` below its standing height, a sole tilted more
        than ``FALL_SOLE_TILT`` or the root more than ``FALL_ROOT_TILT`` (False for a fixed base)."""
        if self.drop is None:
            return False
        return bool(
            self.drop.max() > FALL_DROP
            or self.sole_tilt.max() > FALL_SOLE_TILT
            or self.root_tilt.max() > FALL_ROOT_TILT
        )


def play(robot: RehearsalRobot, commands: Commands, added: Callable | None = None) -> Played:
    """Stand (a standing robot: ``SETTLE`` s) at the first sample, then play ``commands`` on ``robot``.

    Args:
        robot: :func:`~excite_cli.rehearsal.mujoco_robot.rehearsal_robot`'s.
        commands: the export's samples at the controller's rate.
        added: ``added(k, data)`` before each tick adds forces of its own to ``data.qfrc_applied`` or
            ``data.xfrc_applied`` (a push, a stabilizer), k the sample (None while standing still first).

    Returns:
        What MuJoCo measured at each tick (:class:`Played`).
    """
    mujoco = import_mujoco()
    model = robot.model
    data = mujoco.MjData(model)
    held = list(robot.held)
    pose(model, data, robot.held | dict(zip(robot.active, commands.q[0])))
    qpos = _addresses(model, robot.active, model.jnt_qposadr)
    dofs = _addresses(model, robot.active, model.jnt_dofadr)
    held_dofs = _addresses(model, held, model.jnt_dofadr)
    moved = np.array([model.actuator(name).id for name in robot.active])
    held_actuators = np.array([model.actuator(name).id for name in held], dtype=int)
    damping = np.array([robot.gains[j][1] for j in robot.active])
    data.ctrl[held_actuators] = [robot.held[j] for j in held]
    ticks = max(1, int(round(1.0 / (commands.rate * model.opt.timestep))))
    held_tau = commands.held_tau

    driven = np.r_[dofs, held_dofs]
    driven_damping = np.array([robot.gains[j][1] for j in [*robot.active, *held]])

    def tick(k: int, settling: bool = False) -> np.ndarray:
        """One tick; the joint forces [N·m] the actuators applied, their mean over its MuJoCo steps."""
        data.ctrl[moved] = commands.q[k]
        data.qfrc_applied[:] = 0.0
        data.qfrc_applied[dofs] = commands.tau[k] + damping * commands.qd[k]  # the PD's D acts on q̇_ref − q̇
        if held_tau is not None and len(held):
            data.qfrc_applied[held_dofs] += held_tau[k]
        if added is not None:
            added(None if settling else k, data)
        if settling:
            mujoco.mj_step(model, data, ticks)
            return data.qfrc_applied
        applied = np.zeros(model.nv)
        for _ in range(ticks):  # the PD's damping is implicit (implicitfast): its force at the step's end velocity
            before = data.qvel[driven].copy()
            mujoco.mj_step(model, data)
            applied += data.qfrc_actuator + data.qfrc_applied
            applied[driven] -= driven_damping * (data.qvel[driven] - before)
        return applied / ticks

    mujoco.mj_forward(model, data)
    posed = float(data.qpos[2]) if robot.standing else 0.0
    soles = sorted({int(model.geom_bodyid[g]) for g in range(model.ngeom) if model.geom_bodyid[g] > 0})
    contacts = np.zeros((0, 2))
    for _ in range(int(round(SETTLE * commands.rate)) if robot.standing else 1):
        tick(0, settling=True)
        if data.ncon > len(contacts):  # the soles' contacts while most of them touch
            contacts = np.array([data.contact[i].pos[:2] for i in range(data.ncon)])
    at_rest = set(_touching(mujoco, model, data))
    count = len(commands.q)
    n, h = len(robot.active), len(held)
    q, qd, tau, tau_held = np.zeros((count, n)), np.zeros((count, n)), np.zeros((count, n)), np.zeros((count, h))
    first: dict[tuple[str, str], float] = {}
    standing = _Standing(mujoco, model, data, soles, posed, contacts) if robot.standing else None
    for k in range(count):
        q[k], qd[k] = data.qpos[qpos], data.qvel[dofs]  # what the controller measures at tick k
        applied = tick(k)
        tau[k], tau_held[k] = applied[dofs], applied[held_dofs]
        if not robot.standing:
            for pair in _touching(mujoco, model, data):
                if pair not in at_rest:
                    first.setdefault(pair, k / commands.rate)
        else:
            standing.measure(k)
    time = np.arange(count) / commands.rate
    fields = standing.fields(count) if standing else {}
    return Played(time, q, qd, tau, tau_held, first, tuple(sorted(at_rest)), **fields)


def held_in_order(robot: RehearsalRobot, names: tuple[str, ...], tau: np.ndarray) -> np.ndarray:
    """(S, h) the held joints' feed-forward ``tau`` (S, len(names)) [N·m] in ``robot.held``'s order, 0 for a
    held joint ``names`` lacks."""
    columns = {name: i for i, name in enumerate(names)}
    return np.column_stack([tau[:, columns[j]] if j in columns else np.zeros(len(tau)) for j in robot.held])


def _addresses(model, names: list[str], table: np.ndarray) -> np.ndarray:
    return np.array([table[model.joint(name).id] for name in names], dtype=int)


def _touching(mujoco, model, data) -> list[tuple[str, str]]:
    """(body, body) of MuJoCo's contacts, each pair sorted (the world is ``world``)."""
    found = []
    for i in range(data.ncon):
        contact = data.contact[i]
        if contact.dist > 0:  # within the margin, not touching
            continue
        a, b = (model.body(int(model.geom_bodyid[g])).name or "world" for g in contact.geom)
        found.append(tuple(sorted((a, b))))
    return found


class _Standing:
    """The centre of pressure, tilts and drop of a standing robot, tick by tick."""

    def __init__(self, mujoco, model, data, soles: list[int], posed: float, contacts: np.ndarray) -> None:
        self.mujoco, self.model, self.data, self.soles = mujoco, model, data, soles
        self.root = int(model.jnt_bodyid[0])
        self.height = float(data.qpos[2]) if data.ncon >= 3 else posed  # fell standing still: from where posed
        if data.ncon >= 3:
            contacts = np.array([data.contact[i].pos[:2] for i in range(data.ncon)])
        self.polygon = SupportPolygon.from_points(contacts, 0.0)
        self.upright = [data.xmat[b].reshape(3, 3)[:, 2].copy() for b in soles + [self.root]]
        self.cop, self.com, self.tilt, self.drop = [], [], [], []

    def measure(self, k: int) -> None:
        data = self.data
        self.cop.append(_centre_of_pressure(self.mujoco, self.model, data))
        self.com.append(data.subtree_com[self.root, :2].copy())
        self.tilt.append(
            [
                np.degrees(np.arccos(np.clip(data.xmat[b].reshape(3, 3)[:, 2] @ z, -1.0, 1.0)))
                for b, z in zip(self.soles + [self.root], self.upright)
            ]
        )
        self.drop.append(self.height - data.qpos[2])

    def fields(self, count: int) -> dict:
        tilt = np.array(self.tilt).reshape(count, -1)
        return {
            "cop": np.array(self.cop).reshape(count, 2),
            "com": np.array(self.com).reshape(count, 2),
            "polygon": self.polygon,
            "sole_tilt": tilt[:, :-1].max(axis=1),
            "root_tilt": tilt[:, -1],
            "drop": np.array(self.drop),
        }


def _centre_of_pressure(mujoco, model, data) -> np.ndarray:
    """(2,) world x, y [m] of the floor's contact forces' centre of pressure (NaN with no contact)."""
    pressure, total, force = np.zeros(2), 0.0, np.zeros(6)
    for i in range(data.ncon):
        contact = data.contact[i]
        mujoco.mj_contactForce(model, data, i, force)
        up = abs((contact.frame.reshape(3, 3).T @ force[:3])[2])  # friction lies in the floor's plane
        pressure += up * contact.pos[:2]
        total += up
    return pressure / total if total > 0 else np.full(2, np.nan)
