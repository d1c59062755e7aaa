"""What ``check`` and ``init`` print of an optimize problem: its constraints, sizes and estimated time, and
what a starting config assumed."""

from __future__ import annotations

from rich.table import Table

from excite_cli.console.tables import titled_table
from excite_cli.search.run_time import ITERATIONS_PER_COEFFICIENT, expected_rounds
from excite_cli.workflows.check import Plan
from excite_cli.workflows.init import InitRun


def plan(p: Plan) -> list[Table | str]:
    """What ``check`` found: the problem ``optimize`` would run, its constraints and an estimated time."""
    e, cfg = p.excitation, p.excitation.spec
    t = cfg.trajectory
    grid, fine = e.grid_basis.q.shape[0], e.fine_basis.q.shape[0]
    rows = [
        (c.name, str(c.rows), f"{c.smallest_row:.2g} – {c.largest_row:.2g}" if c.rows else "–", c.what)
        for c in p.constraints
    ]
    caption = (
        f"each row aggregated over the {grid}-instant constraint grid ({t.constraint_period:g} s); "
        f"the fine check: {fine} instants; row norms: of the Jacobian rows at the first random start, in "
        "the optimizer's variables (normalized units per half-range of motion)"
    )
    s = p.scaling
    active = (
        f"{s.active} constraint(s) active at the start, their Jacobian's condition number {s.active_condition:.3g}"
        if s.active
        else "no constraint active at the start"
    )
    lines = [
        f"robot: {e.robot.n_joints} active joints ({', '.join(e.robot.joint_names)}), "
        f"{e.base.count} base parameters of {e.robot.n_parameters} standard ones"
        + (f", and {e.effects.count} effect columns beside them ({', '.join(e.effects.names)})" if e.effects else ""),
        f"trajectory: {t.harmonics} harmonics at ω = {t.base_frequency:.4g} rad/s, {t.duration:g} s "
        f"({t.boundary}), {p.variables} Fourier coefficients; cost: {t.cost_samples} samples × "
        f"{e.robot.n_rows} rows = C of {t.cost_samples * e.robot.n_rows} × {e.columns}",
        *(f"excluded capsule pair: {a} – {b}" for a, b in p.excluded_pairs),
        *(
            f"environment shape {name}: out of every moving capsule's reach by more than its margin, in any "
            "posture: no rows (nothing to keep)"
            for name in p.unreached
        ),
        f"noise: {e.noise.words if e.noise else 'none declared, every row weighs the same'}",
        f"optimizer: {cfg.optimizer.method} on {cfg.optimizer.objective}, {cfg.sequence.iterations} sequential "
        f"iteration(s) of at most {p.iterations} solver iterations each, on {p.workers} worker(s)",
        f"scaling: the criterion's largest gradient component {s.gradient:.3g} per half-range, scaled by "
        f"{s.scale:.3g} for the solver (a first step of at most 0.1 half-range); {active}",
        *_time(p),
        "the home posture meets every constraint: optimize would start",
    ]
    return [titled_table("Constraints", ("constraint", "rows", "row norms", "what"), rows, caption), *lines]


def _time(p: Plan) -> list[str]:
    """The estimated time, what it is made of and what would cut it."""
    cfg, t, e = p.excitation.spec.optimizer, p.timing, p.excitation
    solver, runs = expected_rounds(cfg, p.workers, t)
    total = sum(t.pieces.values())
    shares = sorted(t.pieces.items(), key=lambda item: -item[1])
    screened = f"{cfg.screened} starts screened for {cfg.screen_iterations}, " if cfg.screened else ""
    return [
        f"estimated time: about {_duration(p.estimate)}, at most {_duration(p.at_most)} "
        f"({t.iteration * 1e3:.0f} ms per solver iteration and {t.run:.1f} s per run, timed on this problem; "
        f"{solver} solver iterations and {runs} runs per sequential iteration on the busiest of {p.workers} "
        f"worker(s): {screened}{cfg.restarts} restart(s) of at most {cfg.max_iterations}, expected to converge "
        f"after {ITERATIONS_PER_COEFFICIENT} per Fourier coefficient, no polish round; at most: every restart to "
        f"its limit and {cfg.polish_rounds} polish round(s))",
        "of one evaluation (criterion and constraints with their derivatives, "
        f"{total * 1e3:.0f} ms on the {e.grid_basis.q.shape[0]}-instant grid): "
        + ", ".join(f"{name} {100 * share / total:.0f} %" for name, share in shares),
        "to cut the time: fewer starts and restarts (optimizer.starts, optimizer.restarts) or iterations "
        "(optimizer.max_iterations); a coarser constraint grid (trajectory.constraint_period) for the constraints' "
        "share; fewer capsules (constraints.self_collision.ignore_links) for self_collision's",
    ]


def initialized(run: InitRun) -> list[Table | str]:
    """What ``init`` wrote and assumed, then the dry run of an ``optimize`` config."""
    draft = run.draft
    lines = [f"wrote {run.target}; what it assumed (also as comments in the file):"]
    lines += [f"  {name}: {why}" for name, why in draft.assumptions.items()]
    lines += [f"  excluded pair {a} – {b}: {why}" for a, b, why in draft.excluded]
    lines += [f"  mounting plane ignores {link}: {why}" for link, why in draft.ignored]
    if draft.problem:
        return [*lines, f"next: fix what it marks FIX FIRST, then excite check {run.target}"]
    if run.plan is None:
        filled = not any("FILL IN" in why for why in draft.assumptions.values())
        return [*lines, f"{'next' if filled else 'fill in what it marks FILL IN, then'}: excite identify {run.target}"]
    return [*lines, *plan(run.plan), f"next: excite optimize {run.target}"]


def _duration(seconds: float) -> str:
    """``42 s``, ``3.5 min`` or ``1.2 h``."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.1f} min" if seconds < 5400 else f"{seconds / 3600:.1f} h"
