"""Does the effect search admit only what the data hold? Distinct random feasible trajectories of a
config (excite's simulator, 10 s at 200 Hz each, 0.2 mrad encoder noise, torque noise 0.05 N·m + 1 %
of the torque), truth ``friction``: Coulomb 0.6 N·m and viscous 0.4 N·m·s/rad on every joint;
``stribeck``: and Stribeck friction of 0.35 N·m (v_s 0.1 rad/s) on the middle joint; ``spring``: and
a 100 N·m/rad spring on the middle joint; ``coulomb``: Coulomb friction alone (no viscous friction
anywhere, for the friction a search's end gets back). N recordings fitted with nothing declared (the default
search, folds the recordings: the paired test) and one more for validation; beside it the truth's
terms declared and fitted without a search on the same data (the true model's floor).

Printed per N: the runs that admitted a term the truth lacks (and which), the runs that found the
truth's Stribeck or spring term, the largest ratio of the validation error to the true model's, and
the mean identify time.

Run: `.venv/bin/python bench/admission.py CONFIG [--recordings 4 6 8] [--seeds 0 1 ...] [--truth
friction|coulomb|stribeck|spring]`. Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.search.sequence import describe
from excite_cli.storage.results import write_result
from excite_cli.workflows.simulate import simulate_runs

FRICTION = {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}}


def truth_effects(truth: str, middle: str) -> dict:
    """The simulated effects of ``truth`` (module docstring), its extra term on joint ``middle``."""
    if truth == "coulomb":  # no viscous friction anywhere
        return {"coulomb": FRICTION["coulomb"]}
    extra = {
        "stribeck": {"stribeck": {middle: 0.35}},
        "spring": {"spring": {middle: 100.0}},
    }.get(truth, {})
    return {**FRICTION, **extra}


def recordings(folder: Path, config: Path, count: int, seed: int, truth: str) -> tuple[list[Path], dict, str]:
    """``count`` distinct random feasible trajectories of ``config``, simulated; its robot section and
    the joint of the truth's extra term."""
    problem = load_problem(config)
    excitation = build_excitation(problem)
    rng = np.random.default_rng(2000 + seed)
    prior = np.zeros((0, excitation.columns))
    results = [describe(excitation, k + 1, excitation.random_start(rng), prior) for k in range(count)]
    write_result(folder / "motions.h5", excitation, results, seed, {"method": "random_selection"})
    joints = list(problem.robot.active_joints)
    middle = joints[len(joints) // 2]
    sim = SimulationConfig(
        sample_rate=200,
        periods=1,
        position_noise=2e-4,
        torque_noise=0.05,
        torque_noise_relative=0.01,
        seed=seed,
        effects=truth_effects(truth, middle),
    )
    robot = {"urdf": problem.robot.urdf, "source": problem.robot.source, "active_joints": joints}
    return simulate_runs(folder / "motions.h5", sim, folder / "runs"), robot, middle


def identify(folder: Path, name: str, runs: list[Path], robot: dict, identification: dict):
    """The identify report on ``runs`` (the last one validation)."""
    joints = robot["active_joints"]
    config = {
        "robot": robot,
        "data": {
            "runs": [
                {"file": str(p), "role": "fit" if k < len(runs) - 1 else "validation"} for k, p in enumerate(runs)
            ],
            "columns": {"q": [f"q_{j}" for j in joints], "tau": [f"tau_{j}" for j in joints]},
        },
        "preprocessing": {"sample_rate": 200},
        "identification": identification,
        "output": str(folder / f"{name}.h5"),
    }
    (folder / f"{name}.yaml").write_text(yaml.safe_dump(config))
    return run_identification(load_problem(folder / f"{name}.yaml", IdentifyProblem))[0]


def one(config: Path, count: int, seed: int, truth: str) -> tuple[list[str], bool, float, float]:
    """(terms the truth lacks, whether the truth's extra term was found, validation error over the true
    model's, identify's wall time [s]) of one set of ``count`` recordings."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        runs, robot, middle = recordings(folder, config, count + 1, seed, truth)
        start = time.perf_counter()
        report = identify(folder, "search", runs, robot, {})
        wall = time.perf_counter() - start
        effects = truth_effects(truth, middle)
        declared = {
            j: [e for e, where in effects.items() if "*" in where or j in where] for j in robot["active_joints"]
        }
        floor = identify(folder, "truth", runs, robot, {"declared_effects": declared, "candidates": []})
    joints = report.joints
    truth_terms = {(e, j) for j, names in declared.items() for e in names}
    extra = [t.label(joints) for t in report.selection.terms if (t.effect, t.where(joints)) not in truth_terms]
    found = truth in ("friction", "coulomb") or any(
        t.effect == truth and t.where(joints) == middle for t in report.selection.terms
    )
    return extra, found, report.mean(report.relative_after) / floor.mean(floor.relative_after), wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("config", type=Path)
    parser.add_argument("--recordings", type=int, nargs="+", default=[4, 6, 8])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(20)))
    parser.add_argument("--truth", choices=["friction", "coulomb", "stribeck", "spring"], default="friction")
    args = parser.parse_args()
    for count in args.recordings:
        rows = []
        for seed in args.seeds:
            rows.append(one(args.config, count, seed, args.truth))
            extra, found, ratio, wall = rows[-1]
            print(
                f"  {count} recordings, seed {seed}: extra {extra or '-'}, found {found}, "
                f"error / true {ratio:.3f}, {wall:.0f} s",
                flush=True,
            )
        admitted = sum(bool(r[0]) for r in rows)
        print(
            f"{args.config.name} {args.truth}, {count} recordings, {len(rows)} seeds: a term the truth lacks in "
            f"{admitted} ({100 * admitted / len(rows):.0f} %), the truth's term found in {sum(r[1] for r in rows)}, "
            f"validation error / true model's at most {max(r[2] for r in rows):.3f}, "
            f"identify {np.mean([r[3] for r in rows]):.0f} s each",
            flush=True,
        )


if __name__ == "__main__":
    main()
