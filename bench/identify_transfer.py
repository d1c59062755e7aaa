"""Does `excite identify`'s default choose the model that holds on motion it never saw? Analogues of
the failure classes of real recordings the project does not ship (issue 42), each identified with
the defaults (nothing declared) and validated on data neither the fit nor the selection used:

- **real Panda, first 20 % fitted**: the shipped real run (../shared) fitted on t ∈ [0, 4.2] s and
  validated on [4.4, 21] s, a poorly excited fit run where least squares overfits;
- **coupled motor**: a UR5 whose motor 6 turns with q5 + q6, motor 6's Coulomb friction (2 Nm at the
  joints) dominating joint 5's residual, joint-side data, nothing declared;
- **spring**: a simulated Panda with Coulomb and viscous friction and a spring of 4 Nm/rad on joint 4;
- **dead channel**: the shipped simulated Panda runs with joint 4's sensor drifting between −0.0004
  and −0.007 Nm;
- **sensor zeros**: two simulated Panda runs whose joint-3 torque sensor was zeroed at +0.4 and
  −0.3 Nm, each fitted and validated on alternate time blocks;
- **shipped simulated runs** and the shipped real Panda splits (phase, blocks), where no position
  effect or coupling should be proposed;
- **MuJoCo's physics** (`bench/mujoco_arm.py`): a Panda and a UR5 compiled by MuJoCo from their URDFs
  with joint damping, frictionloss and armature on every joint and a payload on the flange, playing
  excite trajectories with the feed-forward plus PD; an 18-bit encoder, 1.5 % torque noise; fitted on
  some trajectories, validated on another. Their *true* is the floor: MuJoCo's own parameters through
  excite's preprocessing, nothing fitted; a second line gives the consistent fit's link masses and
  the effects against MuJoCo's;
- **effects judged by the folds** (`bench/distinct_recordings.py`): MuJoCo's Panda with a spring of
  100 Nm/rad on joint 4 recorded on 4 random trajectories, each twice (the folds: a paired test over
  distinct trajectories), the same Panda without a spring on one periodic run (time blocks: the
  price), and a simulated Panda with 0.35 Nm of Stribeck friction on joint 2 on 4 optimized
  trajectories, each twice; each validated on one more trajectory.

Printed per analogue: the mean relative validation error [%] of the rigid body, of the reported
model (with the fit it chose), of the other fit excite computed, and of the true model (its terms
declared, fitted by weighted least squares on the same data) where there is one; what was found.

    .venv/bin/python bench/identify_transfer.py
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import yaml
from coupled_wrist import JOINTS as UR5_JOINTS
from coupled_wrist import ROBOT as UR5_ROBOT
from coupled_wrist import true_error
from distinct_recordings import mujoco_twins, simulated_twins
from mujoco_arm import ArmPhysics, arm_model, floor_error, record

from excite_cli.config import RobotConfig
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.robot import load_robot
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.identification.choice.admission import Admission
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.prepared import prepare_data
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.search.sequence import run_sequence
from excite_cli.storage.results import write_result
from excite_cli.workflows.simulate import simulate_runs

ROOT = Path(__file__).resolve().parent.parent
SHARED = ROOT.parent / "shared" / "data" / "panda-gaz2019" / "exciting_traj_1.csv"
PANDA = [f"panda_joint{k}" for k in range(1, 8)]
PANDA_ROBOT = {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": PANDA}
FRICTION = [Term(e, j) for e in ("coulomb", "viscous") for j in range(7)]
COLUMNS = {"q": [f"q_{j}" for j in PANDA], "tau": [f"tau_{j}" for j in PANDA]}
#: MuJoCo's Panda: joint damping, frictionloss and armature, 1 kg 10 cm beyond the flange.
MUJOCO_PANDA = ArmPhysics(
    damping=np.array([0.6, 0.6, 0.5, 0.5, 0.2, 0.2, 0.1]),
    frictionloss=np.array([0.8, 0.8, 0.6, 0.6, 0.3, 0.3, 0.2]),
    armature=np.array([0.3, 0.3, 0.2, 0.2, 0.05, 0.05, 0.02]),
    payload=(1.0, (0.0, 0.0, 0.207), (2e-3, 2e-3, 1e-3)),
)
#: The spring MuJoCo's Panda has on joint 4 [Nm/rad], about q = 0 (outside the joint's range, −3.07 to
#: −0.07 rad: a preloaded spring, an offset plus a stiffness), and the Stribeck friction the simulated
#: one has on joint 2 [Nm] (v_s 0.1 rad/s, the simulator's default).
SPRING, STRIBECK = 100.0, 0.35


def optimized(folder: Path, config: Path, name: str) -> Path:
    """An optimized trajectory of ``config`` (written to ``folder``/``name``.h5)."""
    problem = load_problem(config)
    excitation = build_excitation(problem)
    write_result(folder / f"{name}.h5", excitation, run_sequence(excitation, problem.sequence.iterations, 0), 0)
    return folder / f"{name}.h5"


def identify(folder: Path, name: str, robot: dict, runs: list[dict], columns: dict, **identification):
    """The report of ``identify`` with the defaults (and ``identification``) on ``runs``."""
    config = {"robot": robot, "data": {"runs": runs, "columns": columns}, "output": str(folder / f"{name}.h5")}
    if identification:
        config["identification"] = identification
    (folder / f"{name}.yaml").write_text(yaml.safe_dump(config))
    problem = load_problem(folder / f"{name}.yaml", IdentifyProblem)
    return problem, run_identification(problem)[0]


def found(report, joints: list[str], watched: tuple[str, ...] = ()) -> str:
    """The position-dependent, coupled and dead things the report names, the terms of the ``watched``
    effects, and how the folds admitted them."""
    terms = [
        t.label(joints)
        for t in report.selection.terms
        if t.kind.position or t.coupling is not None or t.effect in watched
    ]
    dead = [f"dead {joints[j]}" for j in np.flatnonzero(~report.live)]
    text = "; ".join(terms + dead) or "no position effect, coupling or dead channel"
    sel = report.selection
    if sel.admission is Admission.PAIRED:
        gains = [f"{s.fold_gain:.1f} > {s.fold_margin:.1f}" for s in sel.steps if s.term.label(joints) in terms]
        text += f" [paired test over {sel.folds} trajectories" + (f"; fold gain % {', '.join(gains)}" if gains else "")
        text += "]"
    return text


def line(
    name: str,
    problem,
    report,
    joints: list[str],
    truth: list[Term] | None,
    true: float | None = None,
    watched: tuple[str, ...] = (),
) -> None:
    """The analogue's row: rigid, chosen (fit), the other fit, the true model (``truth``'s terms fitted
    by weighted least squares, or the figure ``true``) and what was found."""
    choice = report.fit_choice
    true = true_error(problem, truth, report.live) if truth is not None else true
    other_name, other = (
        ("least squares", report.relative_least_squares)
        if choice.is_consistent
        else ("consistent", report.relative_consistent)
    )
    other_text = f"{report.mean(other):6.2f} ({other_name})" if other is not None else "—"
    true_text = f"{true:6.2f}" if true is not None else "     —"
    print(
        f"{name:<34} {report.mean(report.relative_before):6.2f} {report.mean(report.relative_after):6.2f} "
        f"({choice.name:<18}) {other_text:<24} {true_text}  {found(report, joints, watched)}",
        flush=True,
    )


def panda_runs(folder: Path, smoke: Path, name: str, effects: dict, seed: int = 7, periods: int = 1) -> Path:
    """Simulated Panda runs of the smoke trajectories with ``effects`` (0.05 Nm noise)."""
    sim = SimulationConfig(
        sample_rate=200, periods=periods, torque_noise=0.05, position_noise=2e-4, seed=seed, effects=effects
    )
    simulate_runs(smoke, sim, folder / name)
    return folder / name


def edit_column(path: Path, column: str, change) -> None:
    """Rewrite one column of a CSV run in place: ``change(values)``."""
    table = np.genfromtxt(path, delimiter=",", names=True)
    table[column] = change(table[column])
    names = table.dtype.names
    np.savetxt(path, table.view((float, len(names))), delimiter=",", header=",".join(names), comments="", fmt="%.10g")


def mujoco_analogue(folder: Path, name: str, robot: dict, result: Path, physics: ArmPhysics, roles: list[str]) -> None:
    """Record every iteration of ``result`` (2 periods each) on MuJoCo's arm with ``physics``, identify
    with the defaults (``roles`` of the runs: fit or validation) and print its row and a line of
    the consistent fit's masses and the effects against MuJoCo's."""
    cfg = RobotConfig(**robot)
    model_robot = load_robot(cfg, joint_rows_only=True)
    joints = model_robot.joint_names
    mujoco, model = arm_model(resolve_urdf(cfg)[0], joints, physics)
    runs = record(mujoco, model, model_robot, result, 2, 11, folder, name)
    data = [{"file": str(path), "role": role} for path, role in zip(runs, roles)]
    columns = {"q": [f"q_{j}" for j in joints], "tau": [f"tau_{j}" for j in joints]}
    problem, report = identify(folder, name, robot, data, columns)
    base = compute_base_parameters(model_robot)
    truth = physics.truth(len(joints))
    prepared = prepare_data(problem, model_robot, base, [t for t, _ in truth])
    line(
        f"MuJoCo {name}", problem, report, joints, None, floor_error(prepared, base, physics, model_robot, report.live)
    )
    fit = report.consistent
    masses = fit.standard.reshape(-1, 10)[:, 0] / physics.standard(model_robot).reshape(-1, 10)[:, 0] - 1.0
    print(
        f"    consistent masses against MuJoCo's: {', '.join(f'{100 * m:+.1f}' for m in masses)} % "
        f"(the last with the payload); {effect_errors(report, truth, joints)}",
        flush=True,
    )


def effect_errors(report, truth: list[tuple[Term, float]], joints: list[str]) -> str:
    """Of each kind of effect in ``truth`` ((term, MuJoCo's value)), the largest relative error of the
    consistent fit's value, and the terms not found, in words."""
    fit = report.consistent
    found_values = {(t, coefficient): value for t, coefficient, value, _ in report.effect_values(consistent=True)}
    rotors = dict(zip(fit.rotor_joints, fit.rotors))
    worst, missing = {}, []
    for term, value in truth:
        got = found_values.get((term, term.kind.coefficients[0]))
        if got is None and term.effect == "armature":  # the consistent fit holds every rotor
            got = rotors.get(joints[term.joint])
        if got is None:
            missing.append(term.label(joints))
            continue
        worst[term.effect] = max(worst.get(term.effect, 0.0), abs(got / value - 1.0))
    return (
        "largest effect errors: "
        + ", ".join(f"{effect} {100 * e:.1f} %" for effect, e in worst.items())
        + (f"; not found: {', '.join(missing)}" if missing else "")
    )


def main() -> None:
    print(
        f"{'analogue':<34} {'rigid':>6} {'chosen':>6} {'(fit)':<20} {'other fit':<24} {'true':>6}  found",
        flush=True,
    )
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        smoke = optimized(folder, ROOT / "configs" / "smoke.yaml", "smoke")
        if SHARED.exists():
            real = {"q": [f"q{k}" for k in range(1, 8)], "qd": [f"dq{k}" for k in range(1, 8)]}
            real["tau"] = [f"tau{k}" for k in range(1, 8)]
            for name, runs in (
                ("real Panda, first 20 % fitted", [((0.0, 4.2), "fit"), ((4.4, 21.0), "validation")]),
                ("real Panda, phase split", [((0.0, 7.6), "fit"), ((13.4, 21.0), "fit"), ((7.8, 13.2), "validation")]),
                ("real Panda, blocks split", [(None, "blocks")]),
            ):
                data = [{"file": str(SHARED), "role": role, **({"crop": list(c)} if c else {})} for c, role in runs]
                problem, report = identify(folder, name.replace(" ", "_"), PANDA_ROBOT, data, real)
                line(name, problem, report, PANDA, None)
        else:
            print(f"(real Panda analogues skipped: {SHARED} not found)", file=sys.stderr)

        shipped = [
            {"file": str(ROOT / "data" / "panda_simulated" / f"run_{k}.csv"), "role": r}
            for k, r in ((1, "fit"), (2, "validation"))
        ]
        problem, report = identify(folder, "shipped", PANDA_ROBOT, shipped, COLUMNS)
        line("shipped simulated runs", problem, report, PANDA, FRICTION)

        # a dead channel: the shipped runs with joint 4's sensor drifting near zero
        for k, run in enumerate(shipped, start=1):
            path = folder / f"dead_{k}.csv"
            path.write_text(Path(run["file"]).read_text())
            edit_column(
                path, "tau_panda_joint4", lambda x: -0.0004 - 0.0066 * (0.5 + 0.5 * np.sin(np.linspace(0, 3, x.size)))
            )
            run["file"] = str(path)
        problem, report = identify(folder, "dead", PANDA_ROBOT, shipped, COLUMNS)
        line("dead channel (joint 4 drifting)", problem, report, PANDA, FRICTION)

        # a spring on joint 4
        runs = panda_runs(
            folder,
            smoke,
            "spring",
            {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}, "spring": {"panda_joint4": 4.0}},
            periods=2,
        )
        data = [{"file": str(runs / f"run_{k}.csv"), "role": r} for k, r in ((1, "fit"), (2, "validation"))]
        problem, report = identify(folder, "spring", PANDA_ROBOT, data, COLUMNS)
        line("spring on joint 4", problem, report, PANDA, FRICTION + [Term("spring", 3)])

        # two runs whose joint-3 sensor was zeroed apart
        runs = panda_runs(folder, smoke, "zeros", {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}}, periods=2)
        for k, zero in ((1, 0.4), (2, -0.3)):
            edit_column(runs / f"run_{k}.csv", "tau_panda_joint3", lambda x, zero=zero: x + zero)
        data = [{"file": str(runs / f"run_{k}.csv"), "role": "blocks"} for k in (1, 2)]
        problem, report = identify(folder, "zeros", PANDA_ROBOT, data, COLUMNS)
        line("sensor zeros +0.4 / -0.3 Nm (j3)", problem, report, PANDA, FRICTION + [Term("offset", 2)])

        # a coupled motor whose Coulomb friction dominates joint 5
        ur5 = folder / "ur5.yaml"
        ur5.write_text(
            yaml.safe_dump(
                {
                    "robot": UR5_ROBOT,
                    "trajectory": {"harmonics": 4, "base_frequency": 0.5, "cost_samples": 30, "cost_period": 0.3},
                    "limits": {"position_margin": 0.1, "acceleration": 4.0, "velocity": 2.0},
                    "optimizer": {"max_iterations": 60, "restarts": 3},
                    "sequence": {"iterations": 3},
                    "noise": {"absolute": 0.1},  # every row the same, as these rows were measured (not the hedge)
                }
            )
        )
        coupled = np.eye(6)
        coupled[5, 4] = 1.0
        sim = SimulationConfig(
            sample_rate=500,
            periods=4,
            torque_noise=0.2,
            seed=3,
            motor_effects={
                "armature": {"*": 2e-5},
                "coulomb": {"*": 0.002, "wrist_3_joint": 0.018},
                "viscous": {"*": 2e-5},
            },
            transmission={"gear_ratios": [101.0] * 6, "coupling": coupled.tolist()},
        )
        simulate_runs(optimized(folder, ur5, "ur5"), sim, folder / "wrist")
        data = [
            {"file": str(folder / "wrist" / f"run_{k}.csv"), "role": r}
            for k, r in ((1, "fit"), (2, "fit"), (3, "validation"))
        ]
        columns = {"q": [f"q_{j}" for j in UR5_JOINTS], "tau": [f"tau_{j}" for j in UR5_JOINTS]}
        problem, report = identify(folder, "wrist", UR5_ROBOT, data, columns)
        truth = [Term(e, j) for e in ("armature", "coulomb", "viscous") for j in range(5)]
        line(
            "coupled motor (Coulomb 2 Nm on j5)",
            problem,
            report,
            UR5_JOINTS,
            truth + [Term("motor", 4, None, (0, 0, 0, 0, 1.0, 1.0))],
        )

        mujoco_analogue(folder, "panda", PANDA_ROBOT, smoke, MUJOCO_PANDA, ["fit", "validation"])
        ur5 = ArmPhysics(
            damping=np.array([0.8, 0.8, 0.5, 0.2, 0.2, 0.1]),
            frictionloss=np.array([1.5, 1.5, 1.0, 0.4, 0.4, 0.3]),
            armature=np.array([0.2, 0.2, 0.1, 0.03, 0.03, 0.03]),
            payload=(1.5, (0.0, 0.15, 0.0), (3e-3, 2e-3, 3e-3)),  # 7 cm beyond the flange (y of wrist_3_link)
        )
        mujoco_analogue(folder, "ur5", UR5_ROBOT, folder / "ur5.h5", ur5, ["fit", "fit", "validation"])
        admitted_by_folds(folder)


def admitted_by_folds(folder: Path) -> None:
    """Effects judged by what the folds can show: a spring and a low-speed friction term on distinct
    recordings (a paired test over the folds), and one periodic run without a spring (time blocks,
    admitted by the price)."""
    spring = replace(MUJOCO_PANDA, stiffness=np.array([0, 0, 0, SPRING, 0, 0, 0.0]))
    runs = mujoco_twins(folder, "spring_twins", PANDA_ROBOT, spring)
    problem, report = identify(folder, "spring_twins", PANDA_ROBOT, runs, COLUMNS)
    line(f"MuJoCo spring {SPRING:g} Nm/rad j4, 4 traj. x2", problem, report, PANDA, None)
    print(f"    {effect_errors(report, spring.truth(len(PANDA)) + [(Term('spring', 3), SPRING)], PANDA)}", flush=True)
    runs = mujoco_twins(folder, "periodic", PANDA_ROBOT, MUJOCO_PANDA, trajectories=1, periods=3)
    problem, report = identify(folder, "periodic", PANDA_ROBOT, runs, COLUMNS)
    line("MuJoCo no spring, one periodic run", problem, report, PANDA, None)
    five = yaml.safe_load((ROOT / "configs" / "smoke.yaml").read_text())
    five["sequence"]["iterations"], five["optimizer"]["max_iterations"] = 5, 40
    (folder / "five.yaml").write_text(yaml.safe_dump(five))
    effects = {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}, "stribeck": {"panda_joint2": STRIBECK}}
    runs = simulated_twins(folder, "stribeck", optimized(folder, folder / "five.yaml", "five"), effects)
    problem, report = identify(folder, "stribeck", PANDA_ROBOT, runs, COLUMNS)
    truth = FRICTION + [Term("stribeck", 1, 0.1)]
    line(f"Stribeck {STRIBECK:g} Nm on j2, 4 traj. x2", problem, report, PANDA, truth, watched=("stribeck", "held"))


if __name__ == "__main__":
    main()
