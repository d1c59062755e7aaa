"""``excite rehearse``: each iteration's export played in MuJoCo on the lab's controller, before the robot
moves (:mod:`~excite_cli.rehearsal`): tracking, torques against their limits, contacts, and for a standing
robot its centre of pressure, tilts and whether it stands, beside PD alone on the held joints."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from excite_cli.atomic import MARK, atomic_paths
from excite_cli.config_file import load_problem, result_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.errors import ExciteError
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.inputs import input_file
from excite_cli.plots.rehearsal import plot_rehearsal
from excite_cli.rehearsal.mujoco_robot import RehearsalRobot, rehearsal_robot, require_mujoco
from excite_cli.rehearsal.playing import Commands, held_in_order, play
from excite_cli.rehearsal.report import IterationRehearsal, Rehearsal
from excite_cli.rehearsal.soles import mesh_soles
from excite_cli.storage.export import Export
from excite_cli.storage.joint_map import read_joint_map
from excite_cli.storage.paths import check_folder, check_target
from excite_cli.storage.results import read_alphas
from excite_cli.workflows.export import played_result
from excite_cli.workflows.simulate import torque_noise

#: The fields of an effects file a rehearsal's recording takes.
NOISE = ("torque_noise", "torque_noise_relative", "position_noise", "seed")


def run_rehearse(
    result: Path,
    iteration: int | None = None,
    speed: float = 1.0,
    mjcf: Path | None = None,
    record: Path | None = None,
    plot: Path | None = None,
    force: bool = False,
    progress=None,
    config: Path | None = None,
    joint_names: str | None = None,
    noise: SimulationConfig | None = None,
) -> Rehearsal:
    """Play each iteration (or ``iteration``) of ``result`` as ``excite export`` writes it, ``speed`` times
    as fast, in MuJoCo (``mjcf``: the lab's MJCF, else the robot's file compiled by MuJoCo) with the
    result's ``rehearsal`` controller; ``record`` writes each played run as a CSV ``identify`` reads
    (``rehearsal_<k>.csv``: time, q_<joint>, tau_<joint>: the measured positions and applied torques);
    the picture goes to ``plot`` (default ``<result>_rehearsal.png`` beside it,
    :func:`~excite_cli.plots.rehearsal.plot_rehearsal`). ``progress`` is told, in words, each iteration played.
    ``config``: an optimize config whose ``rehearsal`` section replaces the one the result stores (the
    controller tuned after optimizing). ``joint_names``: the problem's joints as ``mjcf`` names them
    (robot=mjcf pairs, or a YAML map file: :func:`~excite_cli.storage.joint_map.read_joint_map`). With
    ``mjcf`` its joints keep the MJCF's damping, armature and
    dry friction (``rehearsal.joint_losses`` is for a URDF, which has none). ``noise``: an effects file
    (``excite simulate``'s) whose ``torque_noise`` [N·m] and ``position_noise`` [rad], drawn from its
    ``seed``, are added to the recording (the effects themselves are MuJoCo's joints').

    Raises:
        ExciteError: MuJoCo is missing, not an excite result or an iteration it lacks (checked first, with
            the inputs, then the outputs), a speed out of range
            (:func:`~excite_cli.workflows.export.played_result`; one the limits refuse is played and
            reported, :attr:`~excite_cli.rehearsal.report.IterationRehearsal.refused`), a missing ``mjcf``, an
            existing recording without ``force``, ``noise`` without ``record`` or giving more than the
            noise, and as
            :func:`~excite_cli.rehearsal.mujoco_robot.rehearsal_robot`.
    """
    require_mujoco()
    problem = result_problem(result)
    controller = load_problem(config).rehearsal if config else problem.rehearsal
    if mjcf and controller.joint_losses is not None:  # the lab's model of its own joints wins
        controller = controller.model_copy(update={"joint_losses": None})
    stored = sorted(dict(read_alphas(result)))
    if iteration is not None and iteration not in stored:
        raise ExciteError(
            "iteration", f"{result} has iterations {stored}, not {iteration}", iteration, f"one of {stored}"
        )
    iterations = stored if iteration is None else [iteration]
    _check_noise(noise, record)
    urdf, package_dirs = resolve_urdf(problem.robot, problem.folder)
    robot_file = input_file(mjcf, "mjcf") if mjcf else urdf
    mapping = read_joint_map(joint_names) if joint_names else {}
    names = [f"rehearsal_{k}.csv" for k in iterations]
    picture = check_target(plot or result.with_name(f"{result.stem}_rehearsal.png"), "plot", force)
    targets = [check_folder(record, names, "record", force) / n for n in names] if record else []
    excitation = build_excitation(problem)
    zmp = problem.constraints.zmp
    soles = mesh_soles(excitation.robot, list(zmp.support_links)) if problem.robot.floating_base and zmp else None
    robot = rehearsal_robot(
        problem.robot, problem.constraints, robot_file, package_dirs, controller, soles, False, mapping
    )
    effort = excitation.robot.model.effortLimit[excitation.robot.v_idx].astype(float)
    rehearsals = []
    for k in iterations:
        export = played_result(result, k, controller.rate, 1, speed, refuse=False)
        played = play(robot, _commands(export, robot, controller.held_feedforward, controller.rate))
        alone = None
        if robot.standing and controller.held_feedforward:
            alone = play(robot, _commands(export, robot, False, controller.rate))
        points = [c.ground_point(export.q, export.qd, export.qdd) for c in excitation.constraints]
        predicted = next((p for p in points if p is not None), None) if robot.standing else None
        given = dict(zip(export.held.joint_names, export.held.effort)) if export.held is not None else {}
        held_effort = np.array([given.get(j, 0.0) for j in robot.held])
        rehearsals.append(
            IterationRehearsal(k, export, played, alone, effort, held_effort, predicted, tuple(robot.held))
        )
        if progress:
            progress(f"played iteration {k} ...")
    done = Rehearsal(result, controller, rehearsals, robot_file, robot.notes)
    if record:
        done.recordings = _record(done, targets, noise)
    done.plot = plot_rehearsal(picture, done)
    return done


def _commands(export: Export, robot: RehearsalRobot, feedforward: bool, rate: float) -> Commands:
    """The controller's commands from the export: the held joints' feed-forward in the model's order."""
    held_tau = None
    if feedforward and robot.held:
        if export.held is None:
            raise ExciteError(
                "rehearsal.held_feedforward",
                "the result's export has no held-joint feed-forward (its config names no soles)",
                expected="false, or constraints.zmp.support_links in the config",
            )
        held_tau = held_in_order(robot, export.held.joint_names, export.held.tau)
    return Commands(export.q, export.qd, export.tau, held_tau, rate)


def _check_noise(noise: SimulationConfig | None, record: Path | None) -> None:
    """Refuse an effects file that gives more than the recording's noise, or no recording to add it to."""
    if noise is None:
        return
    if record is None:
        raise ExciteError("effects", "the noise is added to a recording", expected="a record folder beside it")
    extra = sorted(noise.model_fields_set - set(NOISE))
    if extra:
        raise ExciteError(
            "effects",
            f"gives {', '.join(extra)}: a rehearsal takes only the file's noise, its robot's damping, friction "
            "and armature are MuJoCo's joints' and its rate the controller's",
            expected=f"only {', '.join(NOISE)}",
        )


def _record(done: Rehearsal, targets: list[Path], noise: SimulationConfig | None) -> list[Path]:
    """Each played run written as a recording (:func:`run_rehearse`), with ``noise``'s added."""
    rng = np.random.default_rng(noise.seed if noise else 0)
    sigma_q, sigma_tau, rho = (
        (noise.position_noise, noise.torque_noise, noise.torque_noise_relative) if noise else (0,) * 3
    )
    with atomic_paths(targets, "record") as temporary:
        for r, tmp in zip(done.iterations, temporary):
            names = r.export.joint_names
            header = ["time"] + [f"q_{j}" for j in names] + [f"tau_{j}" for j in names]
            q = r.played.q + rng.normal(0.0, sigma_q, r.played.q.shape)
            tau = r.played.tau + rng.normal(0.0, 1.0, r.played.tau.shape) * torque_noise(sigma_tau, rho, r.played.tau)
            table = np.column_stack([r.played.time, q, tau])
            with open(tmp, "w") as f:
                np.savetxt(f, table, delimiter=",", header=",".join(header), comments="", fmt="%.10g")
                f.write(f"# {MARK} rehearse: iteration {r.iteration} of {done.result.name} played in MuJoCo\n")
    return targets
