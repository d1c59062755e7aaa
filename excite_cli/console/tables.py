"""What ``optimize``, ``check``, ``compare-random``, ``verify-gradient`` and ``export`` print: rich tables built
from what the library returns."""

from __future__ import annotations

from typing import Sequence

import numpy as np
from rich.markup import escape
from rich.table import Table

from excite_cli.config import OptimizerConfig
from excite_cli.criteria import CRITERIA
from excite_cli.search.sequence import IterationResult
from excite_cli.workflows.compare import Comparison
from excite_cli.workflows.verify_gradient import Verification

#: Fine-check figures Table I shows where the run has them: key, column, scale, decimals, caption.
FINE_FIGURES = (
    ("com_max_excursion_m", "CoM [cm]", 100.0, 2, ""),
    ("zmp_min_margin_m", "ZMP [mm]", 1000.0, 1, "; ZMP: the zero-moment point's least distance inside the soles"),
    ("min_capsule_distance_m", "dist [cm]", 100.0, 2, ""),
)


def titled_table(title: str, columns: Sequence[str], rows: Sequence[Sequence[str]], caption: str = "") -> Table:
    """A table whose text is shown as written (brackets such as ``[Nm]`` or ``tau0[run.csv]`` are
    not rich markup)."""
    table = Table(title=escape(title), caption=escape(caption) if caption else None)
    for column in columns:
        table.add_column(escape(column), justify="right")
    for row in rows:
        table.add_row(*(escape(cell) for cell in row))
    return table


def iterations(
    results: Sequence[IterationResult],
    optimizer: OptimizerConfig | None = None,
    improved: Sequence[tuple[str, float, float]] = (),
) -> list[Table]:
    """Table I (cond per iteration, violations, CoM and capsule figures, transitions, time, stop
    reason of the kept restart), every restart's convergence (start and end value of the criterion
    ``optimizer.objective`` and ``scaling`` optimized, first-order optimality, active constraints,
    solver iterations, stop reason) and, with measured prior data, the coefficients the new
    trajectories determine better (``improved``: name, predicted std before and after)."""
    extra = [figure for figure in FINE_FIGURES if results and figure[0] in results[0].checks]
    rows = []
    for r in results:
        ok = float(r.checks.get("transition_max_violation", -np.inf)) <= 0.0
        moves = (
            f"{r.checks.get('transition_in_s', 0.0):.1f}/{r.checks.get('transition_out_s', 0.0):.1f}"
            if ok
            else "violated"
        )
        rows.append(
            (
                str(r.index),
                f"{r.cond_own:.1f}",
                f"{r.cond_stacked:.1f}",
                f"{r.scaled_cond_stacked:.4g}",
                f"{r.excitation_stacked:.3g}",
                f"{r.max_violation:+.1e}",
                *[f"{scale * float(r.checks[key]):.{digits}f}" for key, _, scale, digits, _ in extra],
                moves,
                "-" if np.isnan(r.max_correlation) else f"{r.max_correlation:.2f}",
                f"{r.wall_time_s:.0f}",
                r.stop,
            )
        )
    table = titled_table(
        "Condition numbers (Table I)",
        (
            "iter",
            "cond(C(i))",
            "cond(C)",
            "cond(CL)",
            "ē(C) [Nm]",
            "max viol.",
            *[label for _, label, _, _, _ in extra],
            "in/out [s]",
            "corr.",
            "time [s]",
            "stop",
        ),
        rows,
        "cond(C): on the base columns (the paper's), the effect columns beside them with effects, every row as it is "
        "where the design weighs the rows by their noise; cond(CL) and ē: condition number and excitation "
        "(geometric mean of the singular values) of the URDF-scaled regressor, which do not depend on the "
        "choice of base columns; in/out: quintic transitions from and to the home posture at "
        "rest (checked on the fine grid); corr.: largest correlation of the motion with an earlier iteration's "
        "(1: the same motion again); stop: why the kept restart ended" + "".join(f[4] for f in extra),
    )
    convergence = _restarts(results, optimizer or OptimizerConfig())
    tables = [table, convergence] if convergence.row_count else [table]
    if improved:
        tables.append(
            titled_table(
                "What the new trajectories determine better",
                ("coefficient", "std, measured runs", "std, with the new runs", "ratio"),
                [(escape(n), f"{b:.3g}", f"{a:.3g}", f"{b / a:.3g}×" if a > 0 else "-") for n, b, a in improved],
                "predicted standard deviations of least squares (SI units), from the measured runs' rows alone and "
                "stacked with the new trajectories' (recorded at the same rate, with the same noise per joint)",
            )
        )
    return tables


def _restarts(results: Sequence[IterationResult], optimizer: OptimizerConfig) -> Table:
    """Every restart of every iteration: start and end value of the criterion optimized, KKT
    residual, active constraints, solver iterations, end point, stop reason."""
    matrix = "CL" if optimizer.scaling_of(optimizer.objective) == "urdf" else "C"
    record = CRITERIA[optimizer.objective]
    shown, label = record.shown, f"{record.label}({matrix})"
    restarts = [
        (
            str(r.index),
            str(s.index) + ("*" if s is r.best else ""),
            f"{shown(s.start_objective):.4g}",
            f"{shown(s.objective):.4g}",
            f"{s.optimality.residual:.1e}",
            str(s.optimality.active),
            str(s.iterations),
            s.end,
            s.stop,
        )
        for r in results
        for s in r.restarts
    ]
    return titled_table(
        "Restarts",
        (
            "iter",
            "restart",
            f"start {label}",
            f"end {label}",
            "KKT residual",
            "active",
            "iterations",
            "end point",
            "stop",
        ),
        restarts,
        "*: kept (the best of those that succeeded: a solver failure, or an end at the start or towards "
        "it, is never kept); KKT residual: first-order optimality at the end point (0 at a local optimum); "
        "end point: the feasible point nearest the solver's last iterate (projected), the best iterate "
        "inside (inside), towards the start (bisection), the start, or the earlier iteration's motion it "
        "started from (earlier optimum: run when every restart ended worse than playing that motion again)",
    )


def comparison(c: Comparison) -> list[Table]:
    """Table II beside Table I, and the greedy cond against pool size."""
    rows = [
        (
            str(r["iteration"]),
            f"{r['cond_own']:.1f}",
            f"{r['cond_stacked']:.1f}",
            f"{o['cond_own']:.1f}",
            f"{o['cond_stacked']:.1f}",
            f"{r['cond_stacked'] / o['cond_stacked']:.1f}",
        )
        for r, o in zip(c.random_table, c.optimized_table)
    ]
    side = titled_table(
        f"Table II (random, {c.pool} feasible of {c.drawn} drawn) beside Table I (optimized)",
        ("motion", "rand cond(C(i))", "rand cond(C)", "opt cond(C(i))", "opt cond(C)", "ratio"),
        rows,
        f"wall time: random {c.random_time_s:.0f} s, optimized {c.optimized_time_s:.0f} s; "
        "ratio = random/optimized cond(C)",
    )
    count = len(c.random_table)
    pools = titled_table(
        "Random selection: best cond(C) against pool size",
        ("pool", *[f"cond(C) at {k}" for k in range(1, count + 1)]),
        [(str(size), *[f"{x:.1f}" for x in conds]) for size, conds in c.convergence],
    )
    return [side, pools]


def verification(v: Verification, tolerance: float) -> list[Table | str]:
    """The gradient table, the constraint-Jacobian table and the PASS/FAIL line."""
    gradients = titled_table(
        "Analytic gradient vs finite differences",
        (
            "point",
            "objective",
            "vars",
            "value",
            "err central",
            "err 1-sided",
            "analytic [s]",
            "FD 1-sided [s]",
            "ratio",
        ),
        [
            (
                label,
                name,
                str(c.variables),
                f"{c.value:.4g}",
                f"{c.error_central:.2e}",
                f"{c.error_forward:.2e}",
                f"{c.analytic_s:.4f}",
                f"{c.forward_s:.3f}",
                f"{c.speedup:.0f}×",
            )
            for label, name, c in v.gradients
        ],
    )
    jacobians = titled_table(
        "Constraint Jacobians vs central differences (random trajectory at 90 % of the limits)",
        ("constraint", "rows", "rel. error"),
        [(name, str(rows), f"{e:.2e}") for name, rows, e in v.jacobians],
    )
    verdict = "PASS" if v.worst <= tolerance else "FAIL"
    return [gradients, jacobians, f"{verdict}: largest relative error {v.worst:.2e} (tolerance {tolerance:.0e})"]
