"""The data ``identify`` works on: every configured run read, cut at its gaps, preprocessed (one
cut-off for all), split into fit and validation datasets with the candidate effects' columns, the
trajectory each run records (named, or recordings of one motion together:
:mod:`~excite_cli.identification.measured.twins`), and checked to excite every base parameter."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.channels import dead_channels
from excite_cli.identification.fitting.dataset import Dataset, build_datasets, fit_position_range
from excite_cli.identification.fitting.least_squares import joint_weights, least_squares
from excite_cli.identification.fitting.noise_level import noise_gain
from excite_cli.identification.fitting.normal import NormalEquations, excited_rank
from excite_cli.identification.measured.gaps import split_at_gaps
from excite_cli.identification.measured.measurements import check_against_limits, load_run, silent_channels
from excite_cli.identification.measured.payload import payload_parameters
from excite_cli.identification.measured.preprocessing import choose_cutoff, preprocess
from excite_cli.identification.measured.twins import motion_print, trajectory_groups


@dataclass
class Prepared:
    """The data ``identify`` works on: fit and validation datasets (two-stage columns included), the
    runs with fit instants, the cut-off [Hz] and its source, rows dropped per run, decimated rate [Hz],
    the fit data's q range per joint (n, 2) [rad] that guards the position-dependent effects (None
    with ``identification.position_guard`` off or no position effect among the terms), the joints
    whose torque channel carries no signal (n,) and why, in words (one line per such joint), the
    trajectory of each configured run (R,) and, in words, the recordings taken as one trajectory
    (:func:`~excite_cli.identification.measured.twins.trajectory_groups`), and the noise gain of each
    configured run's low-pass (R,) (:func:`~excite_cli.identification.fitting.noise_level.noise_gain`).
    A run cut at its gaps is preprocessed piece by piece and stays one run in the datasets."""

    fit: Dataset
    validation: Dataset
    fitted: list[int]
    cutoff: float
    cutoff_source: str
    dropped: list[tuple[str, int]]
    rate: float
    q_range: np.ndarray | None
    silent: np.ndarray
    silence: list[str]
    trajectories: np.ndarray
    repeats: list[str]
    gains: np.ndarray


def prepare_data(
    problem: IdentifyProblem,
    robot: Robot,
    base: BaseParameters,
    terms: list[Term],
    say: Callable[[str], None] | None = None,
) -> Prepared:
    """Read every run, choose the cut-off, preprocess, build the fit and validation datasets with the
    columns of ``terms`` (known payloads taken out), check the fit data excite every base parameter,
    and add the two-stage load columns from a first rigid-body fit. Runs are released as they are
    decimated; ``say`` is told each run read.

    Raises:
        ExciteError: bad data (see :func:`load_run`, :func:`preprocess`, :func:`build_datasets`), or
            fit runs that do not excite every base parameter.
    """
    cfg = problem.identification
    runs, payloads, sources, prints = [], [], [], []  # lists only: the runs are released as they are preprocessed
    for k, r in enumerate(problem.data.runs):
        if say:
            say(f"reading run {k + 1}/{len(problem.data.runs)} ({r.label})")
        payload = payload_parameters(robot, r.payload, f"data.runs[{k}].payload") if r.payload else None
        run = load_run(r, problem.data, robot.joint_names, problem.folder)
        check_against_limits(run, robot.joint_names, robot.lower, robot.upper, robot.velocity_limit)
        prints.append(motion_print(run.time, run.q))
        pieces = split_at_gaps(run)  # a recording's gaps are never interpolated across
        runs += pieces
        payloads += [payload] * len(pieces)
        sources += [k] * len(pieces)
    silent = silent_channels(runs, robot.joint_names)
    cutoff, source = choose_cutoff(runs, problem.preprocessing)
    dropped = [(r.name, r.dropped) for r in runs if r.dropped]
    samples = [preprocess(runs.pop(0), problem.preprocessing, cutoff) for _ in range(len(runs))]
    gains = np.ones(len(problem.data.runs))
    gains[sources] = [noise_gain(s.filter.sos) for s in samples]  # a run's pieces share its rate
    rate = max(s.filter.rate / s.filter.step for s in samples)
    coulomb = [Term("coulomb", j) for j in range(robot.n_joints)]  # the load column's sign
    guarded = cfg.position_guard and any(t.kind.position for t in terms)  # the range costs a pass over q
    q_range = fit_position_range(samples, problem.data.validation_blocks) if guarded else None
    fit, val, fitted = build_datasets(
        robot,
        base,
        samples,
        terms + coulomb,
        cfg.coulomb_velocity,
        problem.data.validation_blocks,
        payloads,
        q_range=q_range,
        sources=sources,
    )
    silent, silence = dead_channels(robot, base, silent, (fit, val))
    rigid_only = NormalEquations(fit, [])
    rank = excited_rank(rigid_only.system(None, [])[0])
    if rank < base.count:
        raise ExciteError(
            "data",
            f"the fit runs excite {rank} of the {base.count} base parameters; the robot must move "
            "through an exciting trajectory (see `excite optimize`), motionless or small motions cannot identify it",
        )
    first = least_squares(rigid_only, [], joint_weights(rigid_only, cfg.method == "wls"))
    load = [t for t in terms if t.kind.two_stage]
    trajectories, repeats = trajectory_groups(problem.data.runs, problem.folder, prints)
    labels = [r.label for r in problem.data.runs]
    return Prepared(
        fit.with_load_columns(first.x, load),
        val.with_load_columns(first.x, load),
        fitted,
        cutoff,
        source,
        dropped,
        rate,
        q_range,
        silent,
        silence,
        trajectories,
        [
            f"{labels[k]} repeats the motion of {labels[m]}: taken as one trajectory (the folds hold them out "
            "together; name data.runs[].trajectory to say otherwise)"
            for k, m in repeats
        ],
        gains,
    )
