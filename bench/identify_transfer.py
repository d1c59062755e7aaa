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
  effect or coupling should be proposed.

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
from pathlib import Path

import numpy as np
import yaml
from coupled_wrist import JOINTS as UR5_JOINTS
from coupled_wrist import ROBOT as UR5_ROBOT
from coupled_wrist import true_error

from excite_cli.config_file import load_problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.optimization.excitation import build_excitation
from excite_cli.optimization.sequence import run_sequence
from excite_cli.storage.results import write_result
from excite_cli.workflows.simulate import simulate_runs

ROOT = Path(__file__).resolve().parent.parent
SHARED = ROOT.parent / "shared" / "data" / "panda-gaz2019" / "exciting_traj_1.csv"
PANDA = [f"panda_joint{k}" for k in range(1, 8)]
PANDA_ROBOT = {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": PANDA}
FRICTION = [Term(e, j) for e in ("coulomb", "viscous") for j in range(7)]
COLUMNS = {"q": [f"q_{j}" for j in PANDA], "tau": [f"tau_{j}" for j in PANDA]}


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


def found(report, joints: list[str]) -> str:
    """The position-dependent, coupled and dead things the report names."""
    terms = [t.label(joints) for t in report.selection.terms if t.kind.position or t.coupling is not None]
    dead = [f"dead {joints[j]}" for j in np.flatnonzero(~report.live)]
    return "; ".join(terms + dead) or "no position effect, coupling or dead channel"


def line(name: str, problem, report, joints: list[str], truth: list[Term] | None) -> None:
    choice = report.fit_choice
    other_name, other = (
        ("least squares", report.relative_least_squares)
        if choice.is_consistent
        else ("consistent", report.relative_consistent)
    )
    other_text = f"{report.mean(other):6.2f} ({other_name})" if other is not None else "—"
    true_text = f"{true_error(problem, truth, report.live):6.2f}" if truth is not None else "     —"
    print(
        f"{name:<34} {report.mean(report.relative_before):6.2f} {report.mean(report.relative_after):6.2f} "
        f"({choice.name:<18}) {other_text:<24} {true_text}  {found(report, joints)}",
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


if __name__ == "__main__":
    main()
