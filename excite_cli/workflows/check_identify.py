"""``check`` on an ``identify`` config (one with a ``data`` section; :func:`plan_check` tells the kinds
apart): what the identification would read and fit, without fitting.
Each run is read exactly as ``identify`` reads it (so a missing file, a wrong column, NaN or
motor-side signals are refused as the run would refuse them) and summarized: samples, duration,
rate, the signals found; then the robot's base parameters and the effects declared and searched."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from excite_cli.config_file import ConfigKind, load_config, read_yaml
from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.robot import load_robot
from excite_cli.errors import ExciteError
from excite_cli.identification.choice.selection import candidate_terms, motor_couplings
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.measured.gaps import Gap, find_gaps, missing_messages
from excite_cli.identification.measured.measurements import check_against_limits, load_run
from excite_cli.identification.measured.payload import payload_parameters
from excite_cli.identification.pipeline import declared_terms
from excite_cli.workflows.check import Plan, plan_optimize


@dataclass(frozen=True)
class RunSummary:
    """One measured run as ``identify`` reads it: its label (file and crop), role, samples, duration
    [s], median sample rate [Hz], the signals found (``q``, ``qd`` or ``qdd`` when recorded, ``tau``),
    the rows left out (``data.bad_rows: drop``), its gaps (where identify cuts the run, never
    interpolating across: :func:`~excite_cli.identification.measured.gaps.find_gaps`) and the single
    messages missing between them (:func:`~excite_cli.identification.measured.gaps.missing_messages`)."""

    label: str
    role: str
    samples: int
    seconds: float
    rate: float
    signals: tuple[str, ...]
    dropped: int
    gaps: tuple[Gap, ...] = ()
    missing: int = 0


@dataclass
class IdentifyPlan:
    """What ``identify`` would do with ``problem``: the active joints, the base parameters' count,
    the effects declared (labels) and the candidate terms the search may add, the runs, and what the
    robot's URDF made it warn about."""

    problem: IdentifyProblem
    joints: list[str]
    base_parameters: int
    declared: list[str]
    candidates: int
    runs: list[RunSummary]
    warnings: list[str]


def plan_identify(problem: IdentifyProblem) -> IdentifyPlan:
    """Read every run of ``problem`` and build what the identification starts from (module docstring).

    Raises:
        ExciteError: what ``identify`` would refuse before fitting: the robot (:func:`load_robot`),
            a declared effect on a joint that is not active, a payload's frame the robot does not have
            (:func:`payload_parameters`), a run (:func:`load_run`, :func:`check_against_limits`).
    """
    robot = load_robot(problem.robot, problem.folder, joint_rows_only=True, physical=False)
    cfg = problem.identification
    declared = declared_terms(problem, robot)
    couplings = motor_couplings(problem.data.transmission, cfg.coupling_ratios, robot.n_joints)
    runs = []
    for k, config in enumerate(problem.data.runs):
        if config.payload:  # its frame, as identify reads it before anything else
            payload_parameters(robot, config.payload, f"data.runs[{k}].payload")
        run = load_run(config, problem.data, robot.joint_names, problem.folder)
        check_against_limits(run, robot.joint_names, robot.lower, robot.upper, robot.velocity_limit)
        signals = ("q",) + tuple(s for s in ("qd", "qdd") if getattr(run, s) is not None) + ("tau",)
        steps = np.diff(run.time)
        rate = float(1.0 / np.median(steps)) if steps.size else float("nan")
        seconds = float(run.time[-1] - run.time[0])
        runs.append(
            RunSummary(
                config.label,
                run.role,
                run.time.size,
                seconds,
                rate,
                signals,
                run.dropped,
                tuple(find_gaps(run.time)),
                missing_messages(run.time),
            )
        )
    return IdentifyPlan(
        problem,
        list(robot.joint_names),
        compute_base_parameters(robot).count,
        [t.label(robot.joint_names) for t in declared],
        len([t for t in candidate_terms(cfg, robot.n_joints, couplings) if t not in declared]),
        runs,
        list(robot.warnings),
    )


#: Sections only an optimize config has: beside ``data`` they say the file mixes both kinds.
OPTIMIZE_ONLY = ("trajectory", "limits", "constraints", "optimizer", "sequence", "random_baseline")


def plan_check(path: Path, overrides: dict[str, object]) -> Plan | IdentifyPlan:
    """``check``'s plan of the config at ``path``: :func:`plan_identify` for an identify config (one
    with a ``data`` section), else :func:`~excite_cli.workflows.check.plan_optimize` with the command
    line's ``overrides`` (optimize fields).

    Raises:
        ExciteError: an unreadable config; a data section beside optimize sections (``data``); overrides
            given for an identify config; see both plans.
    """
    value, _ = read_yaml(Path(path))
    if not (isinstance(value, dict) and "data" in value):
        return plan_optimize(load_config(path, overrides))
    stray = [name for name in OPTIMIZE_ONLY if name in value]
    if stray:
        raise ExciteError(
            "data",
            f"{Path(path).name} has a data section, which makes it an identify config, beside the optimize "
            f"section(s) {', '.join(stray)}",
            expected="one kind of config: an optimize config without data, or an identify config without those",
        )
    given = [name.split(".")[-1] for name, v in overrides.items() if v is not None]  # the option's own name
    if given:
        raise ExciteError(given[0], "applies to an optimize config; this is an identify config (it has a data section)")
    return plan_identify(load_config(path, None, ConfigKind.IDENTIFY))
