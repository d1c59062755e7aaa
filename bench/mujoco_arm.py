"""An arm in MuJoCo's physics, which nobody here wrote: the analogue of a lab's recording that
`bench/identify_transfer.py` identifies.

MuJoCo compiles the URDF (its bodies keep the URDF's inertias; static bodies fused, as pinocchio
merges the links a locked joint carries), each joint gets a damping (viscous friction), a
frictionloss (dry friction: MuJoCo's soft friction-loss constraint, not excite's smooth sign) and an
armature (rotor inertia), and a payload is fixed to the last link. An excite trajectory is played at
1 kHz by the export's feed-forward torque (RNEA of the URDF, which knows none of these) plus a PD on
the tracking error, held for five steps of MuJoCo's Euler integrator (5 kHz). Recorded at 1 kHz: the
joint angles quantized by an 18-bit encoder, the commanded torque with white noise of 1.5 % of each
joint's RMS torque (MuJoCo documentation: Modeling, Joints; Computation, Constraint model).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from excite_cli.config_file import result_problem
from excite_cli.dynamics.robot import Robot
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.least_squares import predict, torque_errors
from excite_cli.identification.reporting.mjcf_out import urdf_spec, weld_joints
from excite_cli.storage.results import read_alphas
from excite_cli.trajectory.fourier import FourierTrajectory

#: MuJoCo's step [s] and the steps per controller tick (1 kHz).
STEP, TICK = 2e-4, 5
#: The PD on the tracking error [Nm/rad, Nm·s/rad].
GAINS = (200.0, 10.0)
#: One count of an 18-bit encoder [rad].
ENCODER = 2.0 * np.pi / 2**18
#: White torque noise, a fraction of each joint's RMS commanded torque.
TORQUE_NOISE = 0.015


@dataclass(frozen=True)
class ArmPhysics:
    """What MuJoCo's arm has beyond the URDF.

    Attributes:
        damping: (n,) viscous friction [Nm·s/rad]; frictionloss: (n,) dry friction [Nm];
            armature: (n,) rotor inertia [kg·m²], per active joint.
        payload: mass [kg], position (3,) [m] in the last active joint's frame, principal moments (3,)
            [kg·m²] about its centre (axes along the frame's).
        stiffness: (n,) a spring [Nm/rad] per active joint about ``spring_reference`` (n,) [rad]
            (default q = 0), or None.
    """

    damping: np.ndarray
    frictionloss: np.ndarray
    armature: np.ndarray
    payload: tuple[float, tuple[float, float, float], tuple[float, float, float]]
    stiffness: np.ndarray | None = None
    spring_reference: np.ndarray | None = None

    def truth(self, n: int) -> list[tuple[Term, float]]:
        """(term, value) of every effect excite's catalogue names for these fields."""
        fields = {"viscous": self.damping, "coulomb": self.frictionloss, "armature": self.armature}
        return [(Term(effect, j), float(values[j])) for effect, values in fields.items() for j in range(n)]

    def standard(self, robot: Robot) -> np.ndarray:
        """(10·bodies,) the true standard parameters: the URDF's, the payload added to the last body."""
        mass, position, moments = self.payload
        phi = robot.urdf_parameters().copy()
        phi[-10:] += pin.Inertia(mass, np.asarray(position), np.diag(moments)).toDynamicParameters()
        return phi


def arm_model(urdf: Path, active: list[str], physics: ArmPhysics):
    """The ``mujoco`` module and MuJoCo's compiled arm (module docstring): the joints not ``active``
    welded at 0, no contacts, no joint limits."""
    mujoco, spec = urdf_spec(urdf)
    for geom in list(spec.geoms):
        spec.delete(geom)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    weld_joints(mujoco, spec, active, {}, [])
    spec.option.timestep = STEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_LIMIT
    for j, name in enumerate(active):
        joint = spec.joint(name)
        joint.damping = [float(physics.damping[j]), 0.0, 0.0]  # linear; MuJoCo 4's higher powers none
        joint.frictionloss, joint.armature = float(physics.frictionloss[j]), float(physics.armature[j])
        if physics.stiffness is not None:
            joint.stiffness = [float(physics.stiffness[j]), 0.0, 0.0]
            joint.springref = 0.0 if physics.spring_reference is None else float(physics.spring_reference[j])
    mass, position, moments = physics.payload
    spec.joint(active[-1]).parent.add_body(  # its centre of mass at its origin (MuJoCo 4 has no default there)
        name="payload",
        pos=list(position),
        ipos=[0.0, 0.0, 0.0],
        iquat=[1.0, 0.0, 0.0, 0.0],
        mass=mass,
        inertia=list(moments),
        explicitinertial=True,
    )
    return mujoco, spec.compile()


def record(mujoco, model, robot: Robot, result: Path, periods: int, seed: int, folder: Path, prefix: str) -> list[Path]:
    """Play every iteration of the optimize ``result`` ``periods`` times in MuJoCo's arm and write the
    recordings ``folder``/``prefix``_k.csv (time, q_<joint>, tau_<joint>; module docstring)."""
    problem = result_problem(result)
    trajectory = FourierTrajectory(problem.trajectory.harmonics, problem.trajectory.base_frequency)
    rng = np.random.default_rng(seed)
    return [
        play(mujoco, model, robot, trajectory, alpha, periods, rng, folder / f"{prefix}_{k}.csv")
        for k, alpha in read_alphas(result)
    ]


def play(mujoco, model, robot: Robot, trajectory, alpha: np.ndarray, periods: int, rng, path: Path) -> Path:
    """Play the Fourier coefficients ``alpha`` (n, 2N+1) of ``trajectory`` ``periods`` times in MuJoCo's
    arm and write the recording to ``path`` (time, q_<joint>, tau_<joint>; module docstring)."""
    names = robot.joint_names
    qpos = np.array([model.jnt_qposadr[model.joint(name).id] for name in names])
    dofs = np.array([model.jnt_dofadr[model.joint(name).id] for name in names])
    header = ",".join(["time"] + [f"q_{j}" for j in names] + [f"tau_{j}" for j in names])
    time = np.arange(int(round(periods * trajectory.period * 1000.0)) + 1) / 1000.0
    q, qd, qdd = trajectory.basis(time).evaluate(alpha)
    data = mujoco.MjData(model)
    data.qpos[qpos] = q[0]
    measured_q, tau = np.zeros_like(q), np.zeros_like(q)
    for i in range(time.size):
        measured_q[i] = data.qpos[qpos]
        error, rate = q[i] - data.qpos[qpos], qd[i] - data.qvel[dofs]
        tau[i] = robot.torques(q[i], qd[i], qdd[i]) + GAINS[0] * error + GAINS[1] * rate
        data.qfrc_applied[dofs] = tau[i]
        mujoco.mj_step(model, data, TICK)
    tau += rng.normal(0.0, 1.0, tau.shape) * TORQUE_NOISE * np.sqrt(np.mean(tau**2, axis=0))
    encoder = np.round(measured_q / ENCODER) * ENCODER
    np.savetxt(path, np.column_stack([time, encoder, tau]), delimiter=",", header=header, comments="", fmt="%.10g")
    return path


def floor_error(prepared, base, physics: ArmPhysics, robot: Robot, live: np.ndarray) -> float:
    """Mean relative validation error [%] (over the ``live`` joints) of MuJoCo's own arm through excite's
    preprocessing: the true parameters, nothing fitted (the floor no model of excite's can go below
    but by fitting the noise). ``prepared``: :func:`~excite_cli.identification.prepared.prepare_data`
    with the terms of :meth:`ArmPhysics.truth`."""
    truth = physics.truth(robot.n_joints)
    x = np.concatenate([base.from_standard(physics.standard(robot)), [value for _, value in truth]])
    validation = prepared.validation
    measured = validation.tau.reshape(-1, validation.n)
    return float(torque_errors(measured, predict(validation, x, [t for t, _ in truth]))[2][live].mean())
