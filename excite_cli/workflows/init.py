"""``init``: a starting config for one's own robot from its URDF, what was assumed written as comments
in the file; an ``optimize`` config passes the dry run (:func:`plan_optimize`) before it is written."""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from datetime import date
from pathlib import Path
from typing import Optional

import yaml

from excite_cli.atomic import MARK, atomic_path
from excite_cli.config import RobotConfig
from excite_cli.config_file import drafted_problem
from excite_cli.drafting.data_columns import recognized_columns
from excite_cli.drafting.joints import joint_choice
from excite_cli.drafting.noise_source import SOURCES
from excite_cli.drafting.standing import StandOptions
from excite_cli.drafting.starting_config import StartingConfig, draft_config
from excite_cli.dynamics.robot_files import installed_share, open_source, resolve_urdf
from excite_cli.dynamics.source import RobotSource
from excite_cli.errors import ExciteError, FileNotFound
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.measured.bags import is_bag
from excite_cli.identification.measured.files import read_table
from excite_cli.inputs import input_file
from excite_cli.search.engine import default_workers
from excite_cli.search.run_time import sizes_within
from excite_cli.storage.paths import check_target
from excite_cli.workflows.check import Plan, plan_optimize

KINDS = ("optimize", "identify")
#: What an optimize config's whole run may take by default [s].
BUDGET = 300.0


class _Dumper(yaml.SafeDumper):
    """Sections as blocks, lists on one line ([a, b])."""


_Dumper.add_representer(
    list, lambda dumper, data: dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=True)
)


@dataclass
class InitRun:
    """What ``init`` wrote: the config file, the draft with its assumptions, and the dry run of an
    ``optimize`` config (None for ``identify``)."""

    target: Path
    draft: StartingConfig
    plan: Optional[Plan]


def robot_source(urdf: str, target: Path) -> dict:
    """``robot.urdf`` and ``robot.source`` for the URDF named ``urdf``: a file (written relative to the
    config's folder) or a path inside example-robot-data (e.g. ``ur_description/urdf/ur10_robot.urdf``).

    Raises:
        FileNotFound: neither.
    """
    path = Path(urdf)
    if path.is_file():
        return {"urdf": os.path.relpath(path.resolve(), Path(target).resolve().parent), "source": "file"}
    share = installed_share()
    if share is not None and (share / "example-robot-data" / "robots" / urdf).is_file():
        return {"urdf": urdf, "source": "example-robot-data"}
    raise FileNotFound("urdf", urdf, "URDF or MJCF (a file, or a path inside example-robot-data's robots folder)")


def _identify_config(
    robot: dict, source: RobotSource, joints: Optional[list[str]], draft: StartingConfig, runs: list[str], target: Path
) -> None:
    """The identify config of the robot: its joints, and the data section of ``runs`` (files as the
    user named them, written relative to ``target``'s folder; default a CSV ``runs/run_1.csv``): ROS
    bags need no columns (joints matched by name), other files the columns ``excite simulate`` writes
    (which, among bags, are the files' only)."""
    choice = joint_choice(source, joints, source.model())
    active, held = choice.active, choice.held
    draft.assumptions.update(choice.assumptions)
    files = [os.path.relpath(Path(r).resolve(), target.resolve().parent) for r in runs] or ["runs/run_1.csv"]
    bags = [r for r in runs if is_bag(Path(r))]
    draft.config = {
        "robot": {**robot, "active_joints": active, "locked_joints": held},
        "data": {"runs": [{"file": f, "role": "blocks"} for f in files]},
        "identification": {"method": "wls"},
        "output": f"results/{source.path.stem}_identify.h5",
    }
    draft.assumptions["data.runs"] = (
        "each run fitted and validated on alternate time blocks; give others role: fit / validation"
        if runs
        else "FILL IN: your measured runs (CSV, NPZ, MAT, HDF5 or a ROS bag), each fitted and validated on "
        "alternate time blocks; add runs with role: fit / validation"
    )
    if bags:
        draft.assumptions["data.topic"] = "/joint_states: the bags' sensor_msgs/JointState, joints matched by name"
    if runs and len(bags) == len(runs):
        return
    files_read = [r for r in runs if not is_bag(Path(r))]
    found = recognized_columns(read_table(Path(files_read[0])).names, active) if files_read else {}
    default = {"time": "time", "q": [f"q_{j}" for j in active], "tau": [f"tau_{j}" for j in active]}
    draft.config["data"]["columns"] = {**default, **found}
    missing = [signal for signal in default if signal not in found]
    named = ", ".join(signal for signal in found)
    draft.assumptions["data.columns"] = (
        (f"{named} recognized in {Path(files_read[0]).name}; " if found else "")
        + (
            f"FILL IN: the column names of your files for {', '.join(missing)} (these are the ones "
            "`excite simulate` writes); "
            if missing
            else "check them; "
        )
        + ("add qdd" if "qd" in found else "add qd (and qdd)")
        + " if you record them, factors for units other than rad and Nm"
        + ("; the bags' joints are matched by name" if bags else "")
    )


def _existing(runs: list[str]) -> list[str]:
    """``runs`` (files, or a ROS 2 bag's folder), each checked to exist.

    Raises:
        FileNotFound: a run that does not exist.
        ExciteError: a folder that is not a ROS 2 bag (a folder of CSV files: each file is a run).
    """
    for run in runs:
        if not Path(run).exists():
            raise FileNotFound("runs", run, "measured run (a data file or a ROS 2 bag folder)")
        if Path(run).is_dir() and not is_bag(Path(run)):
            raise ExciteError(
                "runs",
                f"{run} is a folder, not a data file or a ROS 2 bag (no metadata.yaml in it)",
                expected="each data file named as a run of its own",
            )
    return runs


def _text(draft: StartingConfig, urdf: str, kind: str) -> str:
    """The YAML with what was assumed as comments above it, one line per field."""
    lines = [f"# {MARK} init: {urdf} ({kind} config), {date.today().isoformat()}: a starting config. What it assumed:"]
    lines += [f"#   {name}: {why}" for name, why in draft.assumptions.items()]
    lines += [f"#   excluded pair {a} – {b}: {why}" for a, b, why in draft.excluded]
    lines += [f"#   environment ignores {link}: {why}" for link, why in draft.ignored]
    to_fill = any("FILL IN" in why for why in draft.assumptions.values())
    lines.append(
        "# Check it with `excite check` before a run; change what your lab knows better."
        if kind == "optimize"
        else f"# {'Fill in what is marked FILL IN' if to_fill else 'Check it'}, then run `excite identify`; "
        "change what your lab knows better."
    )
    body = yaml.dump(
        draft.config, Dumper=_Dumper, sort_keys=False, default_flow_style=False, width=100, allow_unicode=True
    )
    return "\n".join(lines) + "\n" + body


def _sized(draft: StartingConfig, urdf: str, target: Path, plan: Plan, budget: float) -> tuple[str, Plan]:
    """The draft's optimizer sized to ``budget`` [s] (:func:`~excite_cli.search.run_time.sizes_within`, on
    the measured ``plan``'s timing), its text and plan."""
    options, sequence = plan.excitation.spec.optimizer, draft.config["sequence"]["iterations"]
    workers = options.workers or default_workers()
    sized, seconds = sizes_within(budget, options, sequence, workers, plan.timing)
    draft.config["optimizer"].update(sized)
    shape = f"{sized.get('starts', 0)} starts screened, {sized['restarts']} restarts of {sized['max_iterations']}"
    fits = "within" if seconds <= budget else "MORE than"
    draft.assumptions["optimizer"] = (
        f"{shape} solver iterations, at most one polish round: the sequence is expected to take "
        f"{seconds / 60:.1f} min, {fits} the budget of {budget / 60:g} min on {workers} core(s) "
        f"({plan.timing.iteration * 1e3:.0f} ms per solver iteration, timed); more starts find better optima where "
        "time allows"
    )
    text = _text(draft, urdf, "optimize")
    return text, plan_optimize(drafted_problem(yaml.safe_load(text), target), plan.timing, plan.excitation.base)


def run_init(
    urdf: str,
    target: Optional[Path],
    joints: Optional[list[str]] = None,
    kind: str = "optimize",
    force: bool = False,
    runs: Optional[list[str]] = None,
    collision: bool = True,
    package_dirs: Optional[list[str]] = None,
    stance: Optional[dict] = None,
    budget: float = BUDGET,
    torque_from: Optional[str] = None,
):
    """Write a starting config of ``kind`` for ``urdf`` to ``target`` (default ``<file name>.yaml``). An
    ``optimize`` config passes the
    dry run before it is written, unless no home posture was found: then it is written with what binds
    commented (``StartingConfig.problem``) and not checked.

    Args:
        urdf: a URDF or MJCF file, or a path inside example-robot-data's robots folder.
        joints: the active joints (default: every revolute joint that follows no other).
        kind: ``optimize`` (the whole problem, which passes the dry run) or ``identify`` (robot and
            the data section to fill in).
        runs: ``identify``: the measured runs (files or ROS 2 bag folders), each must exist.
        collision: fit capsules and draft a mounting plane from the collision meshes (False: none).
        package_dirs: folders that hold the packages ``package://`` meshes name (``robot.package_dirs``).
        budget: what the whole optimization may take [s] (``check``'s estimate on this machine): the
            optimizer's sizes fit it (:func:`~excite_cli.search.run_time.sizes_within`).
        stance: what the user said of a legged robot's stance, the fields of
            :class:`~excite_cli.drafting.standing.StandOptions` (``soles`` also comma-separated).
        torque_from: ``optimize``: where the lab's joint torques come from
            (:data:`~excite_cli.drafting.noise_source.SOURCES`, default unknown): the drafted ``noise``.

    Raises:
        ExciteError: unknown kind or joint, a URDF not found or that no model can have
            (:meth:`~excite_cli.dynamics.source.RobotSource.check`), an output that may not be written, no
            joint to move (see :func:`draft_config`).
    """
    if kind not in KINDS:
        raise ExciteError("kind", f"'{kind}' is not a config kind", kind, " or ".join(KINDS))
    if not budget > 0:
        raise ExciteError("budget", f"{budget / 60:g} min leaves no time to optimize", budget / 60, "minutes > 0")
    if runs and kind != "identify":
        raise ExciteError("runs", "are the measured runs of an identify config", runs[0], "kind identify")
    if torque_from is not None and torque_from not in SOURCES:
        raise ExciteError("torque_from", f"'{torque_from}' is not a torque source", torque_from, ", ".join(SOURCES))
    if torque_from is not None and kind != "optimize":
        raise ExciteError(
            "torque_from", f"drafts the noise section of an optimize config; this is kind {kind}", kind, "optimize"
        )
    target = check_target(Path(target or f"{Path(urdf).stem}.yaml"), "output", force)
    joints = [j.strip() for given in joints or [] for j in given.split(",") if j.strip()] or None
    robot = robot_source(urdf, target)
    if package_dirs:
        robot["package_dirs"] = [os.path.relpath(Path(d).resolve(), target.resolve().parent) for d in package_dirs]
    stance = StandOptions(**(stance or {}))
    path, folders = resolve_urdf(RobotConfig.model_construct(**robot), target.resolve().parent)
    source = open_source(path, folders)
    if stance.srdf:
        source = source.with_srdf(input_file(stance.srdf, "srdf", "SRDF"))
    source.check([], physical=False)  # before pinocchio, which crashes on some URDFs
    plan = None
    if kind == "optimize":
        soles = [s.strip() for given in stance.soles or [] for s in given.split(",") if s.strip()] or None
        draft = draft_config(
            robot, source, joints, target, collision, replace(stance, soles=soles), torque_from or "unknown"
        )
        text = _text(draft, urdf, kind)
        problem = drafted_problem(yaml.safe_load(text), target)
        plan = None if draft.problem else plan_optimize(problem)
        if plan is not None:
            text, plan = _sized(draft, urdf, target, plan, budget)
    else:
        draft = StartingConfig({})
        _identify_config(robot, source, joints, draft, _existing(runs or []), target)
        text = _text(draft, urdf, kind)
        IdentifyProblem.model_validate(yaml.safe_load(text))
    with atomic_path(target, "output") as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return InitRun(target, draft, plan)
