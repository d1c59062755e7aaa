"""``excite simulate``: measured-like runs from a trajectory result and the URDF model, with effects and
noise from a separate effects file, written as CSV or as ROS 2 bags (``recording``), as ``identify`` reads them.

τ = RNEA(q, q̇, q̈; URDF inertias) + Σ effects + Σ motor effects + N(0, σ_τ²); q is written with
N(0, σ_q²) added and timestamps with uniform jitter. CSV columns: ``time, q_<joint>..., tau_<joint>...``;
a bag: :func:`~excite_cli.storage.rosbag.write_joint_states`.

With a ``transmission`` (m = R q, τ = Rᵀ τ_m), each motor k's effects (``motor_effects``: its rotor
inertia and friction, the motor's own values) act in its coordinate m_k = R_k q: τ += R_kᵀ (I_k m̈_k +
Fc_k tanh(ṁ_k / v_c) + Fv_k ṁ_k), on every joint motor k turns with. ``motor_side`` writes what a
controller records instead: motor angles m and motor torques τ_m = R⁻ᵀ τ, in the same columns.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from excite_cli.atomic import MARK, atomic_paths
from excite_cli.config_file import result_problem
from excite_cli.dynamics.robot import Robot, load_robot
from excite_cli.effects import EFFECTS
from excite_cli.errors import ExciteError
from excite_cli.identification.effects import effect_columns
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.storage.paths import check_folder
from excite_cli.storage.results import read_alphas
from excite_cli.storage.rosbag import check_bag_target, write_joint_states
from excite_cli.trajectory.fourier import FourierTrajectory

#: Most samples in one simulated run.
MAX_SAMPLES = 10_000_000


def effect_torques(
    sim: SimulationConfig, robot: Robot, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, rigid: np.ndarray
) -> np.ndarray:
    """(T, n) torques [Nm] of the effects in ``sim.effects`` ({effect: {joint or "*": value}}) at the
    samples q, q̇, q̈ (T, n) in time order, ``rigid`` (T, n) the rigid-body torques [Nm].

    Raises:
        ExciteError: an unknown joint or a value with the wrong number of coefficients.
    """
    tau = np.zeros_like(q)
    for effect, per_joint in sim.effects.items():
        for name, value in per_joint.items():
            if name != "*" and name not in robot.joint_names:
                raise ExciteError(f"effects.{effect}", f"'{name}' is not an active joint")
            coefficients = np.atleast_1d(np.asarray(value, dtype=float))
            if coefficients.size != len(EFFECTS[effect].coefficients):
                raise ExciteError(
                    f"effects.{effect}.{name}",
                    f"needs {len(EFFECTS[effect].coefficients)} value(s) {EFFECTS[effect].coefficients}",
                )
            for j in range(robot.n_joints) if name == "*" else [robot.joint_names.index(name)]:
                shape = getattr(sim, EFFECTS[effect].shape_field) if EFFECTS[effect].shape_field else None
                cols = effect_columns(effect, q[:, j], qd[:, j], qdd[:, j], sim.coulomb_velocity, shape, rigid[:, j])
                tau[:, j] += cols @ coefficients
    return tau


def motor_torques(sim: SimulationConfig, robot: Robot, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """(T, n) joint torques [Nm] of the motors' effects of ``sim.motor_effects`` ({effect: {joint or
    "*": value}}, a joint naming the motor of its row of R) at the samples q, q̇, q̈ (T, n).

    Raises:
        ExciteError: an unknown joint, gear ratios for another number of joints.
    """
    tau = np.zeros_like(q)
    if sim.transmission is None:
        return tau
    R = sim.transmission.reduction()
    if R.shape != (robot.n_joints,) * 2:
        raise ExciteError("transmission.gear_ratios", f"{R.shape[0]} gear ratios for {robot.n_joints} active joints")
    for effect, per_motor in sim.motor_effects.items():
        for name, value in per_motor.items():
            if name != "*" and name not in robot.joint_names:
                raise ExciteError(f"motor_effects.{effect}", f"'{name}' is not an active joint")
            for k in range(robot.n_joints) if name == "*" else [robot.joint_names.index(name)]:
                m = [x @ R[k] for x in (q, qd, qdd)]
                tau += np.outer(value * effect_columns(effect, *m, sim.coulomb_velocity)[:, 0], R[k])
    return tau


def simulate_runs(
    result: Path, sim: SimulationConfig, out_dir: Path, prefix: str = "run", force: bool = False
) -> list[Path]:
    """Write one run per iteration of ``result`` into ``out_dir``, all or none: CSV files
    (:func:`atomic_paths`) or ROS 2 bag folders (``sim.recording``).

    Args:
        result: an ``optimize`` (or ``compare-random``) HDF5 result.
        sim: the effects file.
        out_dir: folder for ``<prefix>_<k>.csv`` (bags: ``<prefix>_<k>``).
        force: replace existing files (bags: earlier bags).

    Returns:
        The written files.

    Raises:
        ExciteError: not a result, an unknown joint or a wrong coefficient count in the effects,
            non-finite effect values, more than MAX_SAMPLES samples per run, files in the way.
    """
    problem = result_problem(result)
    robot = load_robot(problem.robot, problem.folder, joint_rows_only=True)
    trajectory = FourierTrajectory(problem.trajectory.harmonics, problem.trajectory.base_frequency)
    rng = np.random.default_rng(sim.seed)
    alphas = read_alphas(result)
    shape = (robot.n_joints, trajectory.n_coefficients)
    if alphas[0][1].shape != shape:
        raise ExciteError("result", f"{result} has α of shape {alphas[0][1].shape}, its config needs {shape}")
    bags = sim.recording == "rosbag2"
    names = [f"{prefix}_{k}" + ("" if bags else ".csv") for k, _ in alphas]
    check_folder(out_dir, [] if bags else names, "output_dir", force)
    for name in names if bags else []:
        check_bag_target(out_dir / name, "output_dir", force)
    header = ["time"] + [f"q_{j}" for j in robot.joint_names] + [f"tau_{j}" for j in robot.joint_names]
    count = int(round(sim.periods * trajectory.period * sim.sample_rate)) + 1
    if sim.sample_rate <= trajectory.nyquist_rate:
        raise ExciteError(
            "sample_rate",
            f"{sim.sample_rate:g} Hz cannot represent the trajectory (its highest harmonic needs more than "
            f"{trajectory.nyquist_rate:.3g} Hz)",
            sim.sample_rate,
            f"more than {trajectory.nyquist_rate:.3g} Hz",
        )
    if count > MAX_SAMPLES:
        raise ExciteError(
            "periods",
            f"{sim.periods} period(s) of {trajectory.period:g} s at {sim.sample_rate:g} Hz are {count:,} samples "
            f"per run; expected at most {MAX_SAMPLES:,} (fewer periods or a lower sample_rate)",
        )
    tables = {}
    for k, alpha in alphas:
        time = np.arange(count) / sim.sample_rate
        time[1:-1] += rng.uniform(-sim.timestamp_jitter, sim.timestamp_jitter, count - 2) / sim.sample_rate
        q, qd, qdd = trajectory.basis(time).evaluate(alpha)
        rigid = np.array([robot.torques(*x) for x in zip(q, qd, qdd)])
        tau = rigid + effect_torques(sim, robot, q, qd, qdd, rigid) + motor_torques(sim, robot, q, qd, qdd)
        if sim.motor_side:  # what the controller records: motor angles m = R q, motor torques τ_m = R⁻ᵀ τ
            R = sim.transmission.reduction()
            q, tau = q @ R.T, np.linalg.solve(R.T, tau.T).T
        tau += rng.normal(0.0, 1.0, tau.shape) * torque_noise(sim.torque_noise, sim.torque_noise_relative, tau)
        tables[k] = np.column_stack([time, q + rng.normal(0.0, sim.position_noise, q.shape), tau])
        if not np.all(np.isfinite(tables[k])):
            raise ExciteError("effects", "a value makes non-finite torques (NaN or inf in the effects file?)")
    written = [out_dir / name for name in names]
    if bags:
        n = robot.n_joints
        runs = [(table[:, 0], table[:, 1 : 1 + n], table[:, 1 + n :]) for table in tables.values()]
        return write_joint_states(written, robot.joint_names, runs)
    with atomic_paths(written, "output_dir") as tmps:
        for tmp, table in zip(tmps, tables.values()):
            with open(tmp, "w") as f:  # the header row first, as a recording's; the mark last
                np.savetxt(f, table, delimiter=",", header=",".join(header), comments="", fmt="%.10g")
                f.write(f"# {MARK} simulate: a simulated run\n")
    return written


def torque_noise(sigma: float, rho: float, tau: np.ndarray) -> float | np.ndarray:
    """The torque noise's standard deviation [Nm] at torques ``tau`` (any shape) [Nm]: √(σ² + (ρ τ)²),
    σ itself where ρ is 0."""
    return np.sqrt(sigma**2 + (rho * tau) ** 2) if rho else sigma
