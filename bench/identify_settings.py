"""How much the identified model depends on the preprocessing and selection settings: the real Panda
run of ``../shared/data`` on its two shipped splits, identified with the defaults and with one
setting changed at a time. For each it prints the low-pass cut-off, the mean relative validation
error of the reported model (the model and fit chosen together) and of least squares of the same
effects, the fit chosen, the number of effects and their overlap with the default's ((effect,
joint) pairs shared / all), and the time. These are the figures of docs/figures.md under "Identification on real
data that the selection never saw".

    .venv/bin/python bench/identify_settings.py
    .venv/bin/python bench/identify_settings.py --splits phase
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from excite_cli.config_file import load_problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.pipeline import run_identification

ROOT = Path(__file__).resolve().parent.parent
SPLITS = {"phase": "panda_identify_phase.yaml", "blocks": "panda_identify.yaml"}
#: (label, section, field, value); value "2x" / "3x" multiplies the default cut-off.
SETTINGS = [
    ("default", None, None, None),
    ("cut-off 5 Hz", "preprocessing", "cutoff", 5.0),
    ("cut-off 2 × default", "preprocessing", "cutoff", "2x"),
    ("cut-off 3 × default", "preprocessing", "cutoff", "3x"),
    ("sample_rate 100 Hz", "preprocessing", "sample_rate", 100.0),
    ("sample_rate 500 Hz", "preprocessing", "sample_rate", 500.0),
    ("filter_order 2", "preprocessing", "filter_order", 2),
    ("filter_order 6", "preprocessing", "filter_order", 6),
    ("folds 4", "identification", "folds", 4),
    ("folds 10", "identification", "folds", 10),
    ("min_improvement 0.01", "identification", "min_improvement", 0.01),
]


def identify(config: Path, section: str | None, name: str | None, value, default_cutoff: float | None):
    """One identification with one setting changed; the report."""
    problem = load_problem(config, IdentifyProblem)
    if section is not None:
        if isinstance(value, str):
            value = float(value[0]) * default_cutoff
        setattr(getattr(problem, section), name, value)
    return run_identification(problem)[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--splits", nargs="+", default=list(SPLITS), choices=list(SPLITS))
    args = parser.parse_args()
    for split in args.splits:
        config = ROOT / "configs" / SPLITS[split]
        print(f"\n{split} split ({config.name})")
        print("| setting | cut-off [Hz] | reported | least squares | fit | effects (overlap) | time [s] |")
        print("|---|---|---|---|---|---|---|")
        default = None
        for label, section, name, value in SETTINGS:
            begin = time.perf_counter()
            report = identify(config, section, name, value, None if default is None else default.cutoff)
            pairs = {(t.effect, t.joint) for t in report.selection.terms}
            if default is None:
                default, reference = report, pairs
            overlap = len(pairs & reference) / max(len(pairs | reference), 1)
            print(
                f"| {label} | {report.cutoff:.3g} | {report.relative_after.mean():.2f} % | "
                f"{report.relative_least_squares.mean():.2f} % | {report.fit_choice.name} | "
                f"{len(pairs)} ({overlap:.2f}) | {time.perf_counter() - begin:.0f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
