"""What the epigraph form can see of a multiple singular value: at each kept restart's end of a
robot's sequence, Clarke's residual (search/kkt.py: the weights S of a cluster's subdifferential any
S ⪰ 0 of trace 1) beside the same test with S diagonal in the end point's singular vectors, which is
all the epigraph's bounds can weigh (their multipliers are each singular value's own gradient's
weight, with no cross terms). Where the two differ by much, the solver stops short of a point the
full test would call stationary.

Robots and configs as in bench/robustness.py (its shipped ones, or `excite init`'s); one seed.

    .venv/bin/python bench/clarke_diagonal.py [--robot UR3] [--criterion sigma_min] [--iterations 1] [--seed 0]

Prints per iteration: the kept restart's stop, each extreme's cluster (its size and relative spread),
and both residuals. Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import tempfile
from pathlib import Path

import numpy as np
from robustness import INIT, SHIPPED, config_of

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.search import kkt, nlp
from excite_cli.search.engine import Engine, default_workers
from excite_cli.search.nlp import Evaluations
from excite_cli.search.sequence import run_sequence, stacked_regressors


def diagonal_clarke(clusters, *rest):
    """kkt.clarke_optimality with every cluster's cross terms ∇h_ab (a ≠ b) left out: S diagonal."""
    return kkt.clarke_optimality([c * np.eye(len(c))[:, :, None] for c in clusters], *rest)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--robot", default="UR3", choices=[*SHIPPED, *INIT])
    parser.add_argument("--criterion", default="sigma_min", choices=["sigma_min", "cond", "log_cond"])
    parser.add_argument("--iterations", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        problem = load_problem(config_of(args.robot, Path(folder)))
    problem.optimizer.seed, problem.optimizer.objective = args.seed, args.criterion
    excitation = build_excitation(problem)
    with Engine(excitation, min(default_workers(), problem.optimizer.restarts)) as engine:
        results = run_sequence(excitation, args.iterations, args.seed, engine=engine)
    for number, result in enumerate(results, 1):
        criterion = excitation.criterion(stacked_regressors(excitation, None, results[: number - 1]))
        kept = result.best
        sigma = criterion.singular_values(kept.alpha)
        clusters = kkt.extreme_clusters(sigma, criterion.objective.extremes)
        spread = ", ".join(f"{len(i)} within {sigma[i].max() / sigma[i].min() - 1:.0e}" for i, _ in clusters)
        z = excitation.boundary.to_variables(kept.alpha)
        full = Evaluations(criterion, excitation.constraints, excitation.boundary, kept.objective).kkt(z).residual
        original, nlp.clarke_optimality = nlp.clarke_optimality, diagonal_clarke
        try:
            evaluations = Evaluations(criterion, excitation.constraints, excitation.boundary, kept.objective)
            diagonal = evaluations.kkt(z).residual
        finally:
            nlp.clarke_optimality = original
        print(
            f"{args.robot} ({args.criterion}) seed {args.seed} iteration {number}: kept {kept.stop}, clusters "
            f"{spread}; Clarke residual {full:.1e} (S ⪰ 0), {diagonal:.1e} (S diagonal)"
        )


if __name__ == "__main__":
    main()
