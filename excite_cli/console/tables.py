"""What the commands print: rich tables of results, built from what the library returns."""

from __future__ import annotations

from typing import Sequence

import numpy as np
from rich.markup import escape
from rich.table import Table

from excite_cli.storage.export import Export
from excite_cli.identification.effects import COEFFICIENTS, UNITS as EFFECT_UNITS
from excite_cli.identification.physical import body_properties, pseudo_inertia
from excite_cli.identification.pipeline import effect_values
from excite_cli.identification.selection import MOVE_SIGNS
from excite_cli.workflows.compare import Comparison
from excite_cli.workflows.verify_gradient import Verification
from excite_cli.optimization.sequence import IterationResult


def _table(title: str, columns: Sequence[str], rows: Sequence[Sequence[str]], caption: str = "") -> Table:
    """A table whose text is shown as written (brackets such as ``[Nm]`` or ``tau0[run.csv]`` are
    not rich markup)."""
    table = Table(title=escape(title), caption=escape(caption) if caption else None)
    for column in columns:
        table.add_column(escape(column), justify="right")
    for row in rows:
        table.add_row(*(escape(cell) for cell in row))
    return table


def iterations(results: Sequence[IterationResult], objective: str = "log_cond") -> list[Table]:
    """Table I (cond per iteration, violations, CoM and capsule figures, transitions, time, stop
    reason of the kept restart) and every restart's convergence (start and end value, first-order
    optimality, active constraints, solver iterations, stop reason)."""
    extra = [(key, label) for key, label in (("com_max_excursion_m", "CoM [cm]"), ("min_capsule_distance_m", "dist [cm]"))
             if results and key in results[0].checks]
    rows = []
    for r in results:
        ok = float(r.checks.get("transition_max_violation", -np.inf)) <= 0.0
        moves = f"{r.checks.get('transition_in_s', 0.0):.1f}/{r.checks.get('transition_out_s', 0.0):.1f}" if ok else "violated"
        rows.append((str(r.index), f"{r.cond_own:.1f}", f"{r.cond_stacked:.1f}", f"{r.excitation_stacked:.3g}", f"{r.max_violation:+.1e}",
                     *[f"{100 * float(r.checks[key]):.2f}" for key, _ in extra], moves, f"{r.wall_time_s:.0f}", r.stop))
    table = _table("Condition numbers (Table I)",
                   ("iter", "cond(C(i))", "cond(C)", "ē(C) [Nm]", "max viol.", *[label for _, label in extra], "in/out [s]", "time [s]", "stop"),
                   rows, "ē: excitation that does not depend on the choice of base columns (geometric mean of the singular "
                         "values of the URDF-scaled regressor); in/out: quintic transitions from and to the home posture at "
                         "rest (checked on the fine grid); stop: why the kept restart ended")
    shown, label = (np.exp, "cond(C)") if objective == "log_cond" else ((lambda v: v), objective)
    restarts = [(str(r.index), str(s.index) + ("*" if s is r.best else ""), f"{shown(s.start_objective):.4g}", f"{shown(s.objective):.4g}",
                 f"{s.optimality.residual:.1e}", str(s.optimality.active), str(s.iterations), s.end, s.stop)
                for r in results for s in r.restarts]
    convergence = _table("Restarts", ("iter", "restart", f"start {label}", f"end {label}", "KKT residual", "active", "iterations",
                                      "end point", "stop"), restarts,
                         "*: kept; KKT residual: first-order optimality at the end point (0 at a local optimum); "
                         "end point: the feasible point nearest the solver's last iterate (projected), the best iterate "
                         "inside (inside), towards the start (bisection) or the start")
    return [table, convergence] if restarts else [table]


def comparison(c: Comparison) -> list[Table]:
    """Table II beside Table I, and the greedy cond against pool size."""
    rows = [(str(r["iteration"]), f"{r['cond_own']:.1f}", f"{r['cond_stacked']:.1f}", f"{o['cond_own']:.1f}",
             f"{o['cond_stacked']:.1f}", f"{r['cond_stacked'] / o['cond_stacked']:.1f}") for r, o in zip(c.random_table, c.optimized_table)]
    side = _table(f"Table II (random, {c.pool} feasible of {c.drawn} drawn) beside Table I (optimized)",
                  ("motion", "rand cond(C(i))", "rand cond(C)", "opt cond(C(i))", "opt cond(C)", "ratio"), rows,
                  f"wall time: random {c.random_time_s:.0f} s, optimized {c.optimized_time_s:.0f} s; ratio = random/optimized cond(C)")
    count = len(c.random_table)
    pools = _table("Random selection: best cond(C) against pool size", ("pool", *[f"cond(C) at {k}" for k in range(1, count + 1)]),
                   [(str(size), *[f"{x:.1f}" for x in conds]) for size, conds in c.convergence])
    return [side, pools]


def verification(v: Verification, tolerance: float) -> list[Table | str]:
    """The gradient table, the constraint-Jacobian table and the PASS/FAIL line."""
    gradients = _table("Analytic gradient vs finite differences",
                       ("point", "objective", "vars", "value", "err central", "err 1-sided", "analytic [s]", "FD 1-sided [s]", "ratio"),
                       [(label, name, str(c.variables), f"{c.value:.4g}", f"{c.error_central:.2e}", f"{c.error_forward:.2e}",
                         f"{c.analytic_s:.4f}", f"{c.forward_s:.3f}", f"{c.speedup:.0f}×") for label, name, c in v.gradients])
    jacobians = _table("Constraint Jacobians vs central differences (random trajectory at 90 % of the limits)",
                       ("constraint", "rows", "rel. error"), [(name, str(rows), f"{e:.2e}") for name, rows, e in v.jacobians])
    verdict = "PASS" if v.worst <= tolerance else "FAIL"
    return [gradients, jacobians, f"{verdict}: largest relative error {v.worst:.2e} (tolerance {tolerance:.0e})"]


def export_lines(e: Export, rate: float) -> list[str]:
    """The segments of an exported motion and its constraint check."""
    return [f"{name:>15}: {start:8.3f} s → {start + duration:8.3f} s" for name, start, duration in e.segments] + [
        f"{e.time.size} samples at {rate:g} Hz; every constraint holds: largest normalized violation "
        f"{e.max_violation:+.2e} (≤ 0 satisfied), closest: {e.worst}"]


def validation(name: str, joints: Sequence[str], errors) -> Table:
    """Relative RMS torque error per run and joint of ``validate``."""
    return _table(f"Validation of {name}: relative RMS torque error [%] per run", ("run", "instants", *joints, "mean"),
                  [(e.name, str(e.instants), *[f"{x:.1f}" for x in e.relative], f"{e.relative.mean():.1f}") for e in errors])


def preprocessing_notes(report) -> list[str]:
    """The cut-off used (and where it came from) and the rows dropped per run."""
    return [f"low-pass cut-off {report.cutoff:.3g} Hz ({report.cutoff_source}); stored as cutoff_Hz"] + [
        f"data.bad_rows: dropped {rows} unusable row(s) of {name}" for name, rows in report.dropped]


def identification(report) -> list[Table | str]:
    """The before/after error table, the ladder, the selection's steps, the chosen effects, what was
    absorbed, the base parameters."""
    consistent, sel = report.relative_consistent, report.selection
    extra = consistent is not None
    errors = _table(f"Validation torque error, rigid body only → with the chosen effects ({report.validation_samples} instants "
                    "that neither the fit nor the selection saw)",
                    ("joint", "RMS τ [Nm]", "before [Nm]", "after [Nm]", "before [%]", "after [%]") + (("consistent [%]",) if extra else ()),
                    [(name, f"{report.rms_torque[j]:.3f}", f"{report.rms_before[j]:.3f}", f"{report.rms_after[j]:.3f}",
                      f"{report.relative_before[j]:.1f}", f"{report.relative_after[j]:.1f}", *((f"{consistent[j]:.1f}",) if extra else ()))
                     for j, name in enumerate(report.joints)],
                    f"mean: before {report.relative_before.mean():.1f} %, after {report.relative_after.mean():.1f} %"
                    + (f", physically consistent {consistent.mean():.1f} %" if extra else ""))
    ladder = _table("What each effect bought: mean relative error after each step", ("step", "cross-validated [%]", "validation [%]"),
                    [(label, f"{cv:.2f}", f"{val:.2f}") for label, cv, val in report.ladder],
                    f"cross-validated: {sel.folds} blocked folds of the fit data (what the selection minimizes); "
                    "validation: data it never saw")
    order = {t: k + 1 for k, t in enumerate(sel.terms)}
    effects = _table("Effects, in the order they were added (declared ones first)",
                     ("#", "effect", "joint", "shape [rad/s]", "coefficient", "value", "std"),
                     [(str(order[t]), t.effect, report.joints[t.joint], "" if t.shape is None else f"{t.shape:g}",
                       f"{name} [{EFFECT_UNITS[COEFFICIENTS[t.effect][0]]}]", f"{value:.5g}", f"{std:.2g}")
                      for t, name, value, std in effect_values(report)])
    params = _table("Identified base parameters", ("base parameter", "value", "std"),
                    [(name, f"{value:.5g}", f"{std:.2g}") for name, value, std in zip(report.base_names, sel.fit.x, sel.fit.std)])
    absorbed = ["not separately identifiable (in the span of the base parameters): "
                + ", ".join(t.label(report.joints) for t in sel.absorbed)] if sel.absorbed else []
    return [errors, ladder, *search(report), effects, *absorbed, params]


def search(report, runners_up: int = 2) -> list[Table | str]:
    """Each step of the kept search with its gain and the best moves it did not take (every move
    tried is in the HDF5 report), and the outcome of every start."""
    sel = report.selection
    kept = sel.searches[sel.chosen]
    rows = []
    for k, step in enumerate(sel.steps, start=1):
        others = sorted(((v, m, t) for m, t, v in step.tried if (m, t) != (step.move, step.term)), key=lambda o: o[0])[:runners_up]
        rows.append((str(k), step.label(report.joints), f"{step.gain:.1f}", str(len(step.tried)),
                     "; ".join(f"{MOVE_SIGNS[m]} {t.label(report.joints)} {step.gain_of(v):.1f}" for v, m, t in others)))
    steps = _table(f"Selection steps from the start '{kept.start}' (gain: cut of the cross-validated error [%])",
                   ("step", "move", "gain [%]", "tried", f"next best {runners_up} [gain %]"), rows, f"stopped: {kept.stop}")
    starts = "; ".join(f"{s.start}: {s.cv_error:.2f} % with {len(s.terms)} effects" + (" (kept)" if k == sel.chosen else "")
                       for k, s in enumerate(sel.searches))
    return [steps, f"searches (cross-validated error at their end): {starts}"]


def bodies(report, robot) -> Table:
    """Identified (physically consistent) bodies beside the URDF's, and the active constraints."""
    urdf, fit = robot.urdf_parameters(), report.consistent
    vector = lambda v: " ".join(f"{x:+.3f}" for x in v)  # noqa: E731
    rows = []
    for i, name in enumerate(robot.body_names):
        m, c, _, moments = body_properties(fit.standard[10 * i: 10 * i + 10])
        um, uc, _, umoments = body_properties(urdf[10 * i: 10 * i + 10])
        rows.append((name, f"{m:.3f} / {um:.3f}", f"{vector(c)} / {vector(uc)}",
                     f"{' '.join(f'{x:.2e}' for x in moments)} / {' '.join(f'{x:.2e}' for x in umoments)}", f"{fit.min_eigenvalues[i]:.1e}"))
    plain = [(name, body_properties(fit.unconstrained[10 * i: 10 * i + 10])[0]) for i, name in enumerate(robot.body_names)
             if np.linalg.eigvalsh(pseudo_inertia(fit.unconstrained[10 * i: 10 * i + 10]))[0] <= 0.0]
    return _table(f"Physically consistent bodies (identified / URDF), solver {fit.status}",
                  ("body", "mass [kg]", "CoM [m]", "principal moments about the CoM [kg m²]", "λmin(J)"), rows,
                  "active: " + (", ".join(fit.active) or "none") + "\nplain least squares (same regularization) is not physical for: "
                  + (", ".join(f"{name} (mass {m:.3f} kg)" for name, m in plain) or "none"))
