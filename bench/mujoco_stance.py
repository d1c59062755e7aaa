"""A standing robot in MuJoCo playing a trajectory: the stances the benches compare, on the rehearsal's
robot (excite_cli/rehearsal: MuJoCo compiles the URDF itself, its integrator and soft contacts, the
soles as the only contacts, a floor under them).

The joints the problem does not move are held at their locked values welded (rigid, as excite's model
holds them) or by a joint PD (the stance's compliance), to which the held joints' feed-forward
(:mod:`~excite_cli.design.held_joints`) or an ankle stabilizer that regulates the centre of mass may be
added; each moving joint gets the feed-forward torque plus a PD on the tracking error, one sample per
MuJoCo step.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from excite_cli.config.problem import Problem
from excite_cli.config.rehearsal import GainsConfig, JointLossesConfig, RehearsalConfig
from excite_cli.identification.reporting.mjcf_out import import_mujoco
from excite_cli.rehearsal.mujoco_robot import TIMESTEP, RehearsalRobot, rehearsal_robot
from excite_cli.rehearsal.playing import Commands, Played, held_in_order, play

#: PD gains of the moving joints' tracking [Nm/rad, Nm·s/rad] (beside the feed-forward torque).
TRACKING_GAINS = (200.0, 10.0)

__all__ = ["TIMESTEP", "Stance", "standing_model", "play_standing"]


@dataclass(frozen=True)
class Stance:
    """How the joints that do not move are held at their locked values.

    Attributes:
        stiffness: PD stiffness [Nm/rad], or None: welded (rigid).
        damping: PD damping [Nm·s/rad].
        feedforward: the PD's joints also get the held joints' feed-forward torque (``export``'s).
        stabilizer: (k_p [N·m/m], k_d [N·m·s/m]) of an ankle stabilizer, or None: each sole gets the
            moment ẑ × (k_p e + k_d ė) / (number of soles) from the centre of mass's horizontal offset
            e from where it stood (Kajita et al., *Introduction to Humanoid Robotics*, 2014, ch. 4:
            ankle torque moves the centre of pressure against the CoM's error), through the two
            hinges nearest the sole.
    """

    stiffness: float | None = None
    damping: float = 0.0
    feedforward: bool = False
    stabilizer: tuple[float, float] | None = None

    def __str__(self) -> str:
        if self.stiffness is None:
            return "welded"
        added = "+feedforward" if self.feedforward else ("+stabilizer" if self.stabilizer else "")
        return f"pd{self.stiffness:g}/{self.damping:g}{added}"


def standing_model(
    problem: Problem,
    urdf: Path,
    stance: Stance,
    joint_losses: tuple[float, float, float] = (0.0, 0.0, 0.0),
    soles: dict[str, tuple[np.ndarray, np.ndarray]] | None = None,
) -> RehearsalRobot:
    """The rehearsal's robot of ``problem`` standing in ``stance`` (one sample per MuJoCo step), every
    joint given MuJoCo's ``damping`` [Nm·s/rad], ``armature`` [kg·m²] and ``frictionloss`` [Nm] of
    ``joint_losses``; ``soles`` as :func:`~excite_cli.rehearsal.mujoco_robot.rehearsal_robot`'s."""
    damping, armature, frictionloss = joint_losses
    controller = RehearsalConfig(
        rate=1.0 / TIMESTEP,
        active_gains=GainsConfig(stiffness=TRACKING_GAINS[0], damping=TRACKING_GAINS[1]),
        held_gains=GainsConfig(stiffness=stance.stiffness or 1.0, damping=stance.damping),
        held_feedforward=stance.feedforward,
        joint_losses=JointLossesConfig(damping=damping, armature=armature, frictionloss=frictionloss),
    )
    return rehearsal_robot(problem.robot, problem.constraints, urdf, [], controller, soles, stance.stiffness is None)


def play_standing(
    robot: RehearsalRobot,
    q: np.ndarray,
    qd: np.ndarray,
    tau: np.ndarray,
    held: tuple[tuple[str, ...], np.ndarray] | None = None,
    stabilizer: tuple[float, float] | None = None,
    push: np.ndarray | None = None,
) -> Played:
    """Stand still at the first sample, then play the samples, one per ``TIMESTEP``.

    Args:
        robot: :func:`standing_model`'s.
        q, qd, tau: (S, n) the moving joints' positions [rad], velocities [rad/s] and feed-forward [Nm].
        held: the held joints' names (h,) and feed-forward torques (S, h) [Nm], added to their PD.
        stabilizer: (k_p [N·m/m], k_d [N·m·s/m]) of :attr:`Stance.stabilizer`, or None.
        push: (S, 3) a force [N] (world frame) on the root at each sample, or None.
    """
    held_tau = held_in_order(robot, *held) if held and robot.held else None
    hinges = _ankle_hinges(robot.model) if stabilizer else []
    soles = len({int(robot.model.geom_bodyid[g]) for g in range(robot.model.ngeom) if robot.model.geom_bodyid[g] > 0})
    root = int(robot.model.jnt_bodyid[0])
    start: list[np.ndarray] = []

    def added(k: int | None, data) -> None:
        if k is None:
            return
        if push is not None:
            data.xfrc_applied[root, :3] = push[k]
        if stabilizer:
            com = data.subtree_com[root, :2].copy()
            if not start:
                start.extend([com, com])
            error, rate = np.r_[com - start[0], 0.0], np.r_[(com - start[1]) / robot.model.opt.timestep, 0.0]
            start[1] = com
            moment = np.cross([0.0, 0.0, 1.0], stabilizer[0] * error + stabilizer[1] * rate) / soles
            for joint in hinges:
                data.qfrc_applied[robot.model.jnt_dofadr[joint]] += data.xaxis[joint] @ moment

    return play(robot, Commands(q, qd, tau, held_tau, 1.0 / TIMESTEP), added)


def _ankle_hinges(model) -> list[int]:
    """The two hinge joints nearest each body with contact geometry (its ankle)."""
    mujoco = import_mujoco()
    found = []
    for body in sorted({int(model.geom_bodyid[g]) for g in range(model.ngeom) if model.geom_bodyid[g] > 0}):
        hinges = []
        while body > 0 and len(hinges) < 2:
            for j in range(model.body_jntadr[body], model.body_jntadr[body] + model.body_jntnum[body]):
                if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
                    hinges.append(j)
            body = int(model.body_parentid[body])
        found += hinges[:2]
    return found
