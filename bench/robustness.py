"""Does `excite optimize` end every restart at a result, on any arm, any seed and any criterion? The
sequential generation of each robot's config (its iterations, restarts and screening) with excite's
default criterion, whatever the config names (the Panda's and UR5's name the paper's log cond), or
each criterion given (`--criteria`), for several seeds, on every core.

Robots: the shipped G1 arms, Panda, UR5 and UR10 with a lab's limits (configs/ur10_lab.yaml), and the
configs `excite init` writes for the UR10, UR3, xArm 7 and Unitree Z1 of example-robot-data, as it
writes them. Printed per robot:

- failed: restarts (every start, screened ones included) whose solver failed, or that ended at their
  start or a bisection towards it (`RestartResult.succeeded` false), of all restarts;
- converged: kept restarts (one per iteration, every iteration) whose end point meets
  optimizer.optimality_tolerance (the KKT residual, or Clarke's where cond's or σ_min's extreme singular
  values are multiple), of all kept; and the largest residual of a kept restart;
- spread: how much worse the last iteration's criterion (of the stacked regressor) is on the worst
  seed than on the best, in singular values of C: for log det (−log det(CᵀC)/b, of σ²) the ratio of
  the geometric means of σ (that of the excitation ē), exp(Δ/2), for log cond that of cond(C),
  exp(Δ), minus 1;
- rises: iterations whose stacked criterion (the one the iteration optimized, C₀ above its regressor)
  ended above the iteration before's, of all iterations after the first (the sequence never losing
  ground: 0);
- worst novelty: the largest correlation of an iteration's motion with an earlier one's (1.00: an
  earlier motion played again, search/earlier_optimum.py);
- wall: mean wall time of one seed's run.

One line per robot and criterion: `robust ROBOT (CRITERION): failed F of R restarts, converged C of K
kept, rises U of I, spread S %, worst novelty N, wall W s`.

    .venv/bin/python bench/robustness.py [--robots G1 "UR10 lab" ...] [--seeds 0 1 ...] [--criteria log_det log_trace_inverse:urdf ...]

Asserts nothing. The identification of each seed's trajectories is bench/criteria.py's measure:
`bench/criteria.py configs/ur10_lab.yaml --criteria log_det:none log_cond:none --seeds 0 1 2 3 4`.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from excite_cli.config import OptimizerConfig
from excite_cli.config_file import load_problem
from excite_cli.criteria import NAMES
from excite_cli.design.resolve import build_excitation
from excite_cli.search.engine import Engine, default_workers
from excite_cli.search.kkt import CONVERGED
from excite_cli.search.sequence import run_sequence

ROOT = Path(__file__).resolve().parent.parent
#: A rise of the stacked criterion smaller than this (relative) is rounding: replaying an earlier
#: motion keeps cond(C) to the last bits.
RISE = 1e-9
DEFAULT_OBJECTIVE = OptimizerConfig.model_fields["objective"].default
SHIPPED = {
    "G1": ROOT / "configs" / "g1_arms.yaml",
    "Panda": ROOT / "configs" / "panda.yaml",
    "UR5": ROOT / "configs" / "ur5.yaml",
    "UR10 lab": ROOT / "configs" / "ur10_lab.yaml",
}
INIT = {
    "UR10": "ur_description/urdf/ur10_robot.urdf",
    "UR3": "ur_description/urdf/ur3_robot.urdf",
    "xArm 7": "xarm_description/urdf/xarm7.urdf",
    "Z1": "z1_description/urdf/z1.urdf",
}


def config_of(robot: str, folder: Path) -> Path:
    """The robot's shipped config, or the one `excite init` writes for it in ``folder``."""
    if robot in SHIPPED:
        return SHIPPED[robot]
    path = folder / f"{robot.replace(' ', '_')}.yaml"
    command = [sys.executable, "-m", "excite_cli", "init", INIT[robot], "--output", str(path), "--force"]
    subprocess.run(command, check=True, capture_output=True, cwd=folder)
    return path


def run_robot(robot: str, config: Path, seeds: list[int], criterion: str = DEFAULT_OBJECTIVE) -> str:
    """The robot's line with ``criterion``, ``OBJECTIVE`` or ``OBJECTIVE:SCALING`` (the config's scaling
    unless given; module docstring), after one row per seed."""
    objective, _, scaling = criterion.partition(":")
    restarts = failed = converged = kept = rises = steps = 0
    worst_kkt, worst_correlation, values, walls = 0.0, -1.0, [], []
    for seed in seeds:
        problem = load_problem(config)
        problem.optimizer.seed = seed
        problem.optimizer.objective = objective
        problem.optimizer.scaling = scaling or problem.optimizer.scaling
        excitation = build_excitation(problem)
        workers = min(default_workers(), problem.optimizer.screened or problem.optimizer.restarts)
        begin = time.perf_counter()
        with Engine(excitation, workers) as engine:
            results = run_sequence(excitation, problem.sequence.iterations, seed, engine=engine)
        walls.append(time.perf_counter() - begin)
        for r in results:
            restarts += len(r.restarts)
            failed += sum(not s.succeeded for s in r.restarts)
            kept += 1
            converged += r.best.stop == CONVERGED
            worst_kkt = max(worst_kkt, r.best.optimality.residual)
            if r.correlations:
                worst_correlation = max(worst_correlation, r.max_correlation)
        values.append(results[-1].best.objective)
        path = [r.best.objective for r in results]  # the stacked criterion each iteration optimized
        rises += sum(b > a + RISE * abs(a) for a, b in zip(path, path[1:]))
        steps += len(path) - 1
        print(
            f"  {robot} ({criterion}) seed {seed}: criterion {' → '.join(f'{v:.4f}' for v in path)}, kept KKT "
            f"{' '.join(f'{r.best.optimality.residual:.1e}' for r in results)}, stops "
            f"{', '.join(r.stop for r in results)}, correlations "
            f"{' '.join(f'{r.max_correlation:.2f}' for r in results[1:])}, {walls[-1]:.0f} s",
            flush=True,
        )
    power = 0.5 if problem.optimizer.objective == "log_det" else 1.0  # log det is of σ², the others of σ
    spread = 100.0 * (np.exp(power * (max(values) - min(values))) - 1.0)
    return (
        f"robust {robot} ({criterion}): failed {failed} of {restarts} restarts, converged {converged} of {kept} kept "
        f"(largest KKT {worst_kkt:.1e}), rises {rises} of {steps}, spread {spread:.1f} %, "
        f"worst novelty {worst_correlation:.2f}, "
        f"wall {np.mean(walls):.0f} s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--robots", nargs="+", default=[*SHIPPED, *INIT], choices=[*SHIPPED, *INIT])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    parser.add_argument("--criteria", nargs="+", default=[DEFAULT_OBJECTIVE], help="OBJECTIVE or OBJECTIVE:SCALING")
    args = parser.parse_args()
    for criterion in args.criteria:
        objective, _, scaling = criterion.partition(":")
        if objective not in NAMES or scaling not in ("", "none", "urdf"):
            parser.error(f"--criteria {criterion}: expected one of {', '.join(NAMES)}, optionally :none or :urdf")
    with tempfile.TemporaryDirectory() as folder:
        configs = {robot: config_of(robot, Path(folder)) for robot in args.robots}
        lines = [run_robot(r, configs[r], args.seeds, o) for r in args.robots for o in args.criteria]
    print("\n".join(lines))


if __name__ == "__main__":
    main()
