"""What ``rehearse`` prints: per iteration the tracking and torques per joint, the contacts, and for a
standing robot whether it stands with the lab's controller and with PD alone."""

from __future__ import annotations

import numpy as np
from rich.table import Table

from excite_cli.console.tables import titled_table
from excite_cli.rehearsal.playing import Played
from excite_cli.rehearsal.report import IterationRehearsal, Rehearsal


def rehearsal(r: Rehearsal) -> list[Table | str]:
    """The tables and lines of a rehearsal, the verdict last."""
    c = r.controller
    active, held = c.active_gains, c.held_gains
    items: list[Table | str] = [
        f"MuJoCo's {r.robot_file.name}: active joints on the export's feed-forward + PD {active.stiffness:g}/"
        f"{active.damping:g}, at {c.rate:g} Hz"
        + (f"; held joints on PD {held.stiffness:g}/{held.damping:g}" if r.standing else ""),
        *[f"note: {n}" for n in r.notes],
    ]
    for it in r.iterations:
        items += [_joints(it), *_lines(it, c.held_feedforward)]
    for path in [*r.recordings, r.plot]:
        items.append(f"wrote {path}")
    failed = [it.iteration for it in r.iterations if it.failed]
    items.append(
        f"refused: iteration{'s' if len(failed) > 1 else ''} {', '.join(map(str, failed))} would not play safely"
        if failed
        else f"every iteration played: {len(r.iterations)} of {len(r.iterations)}"
    )
    return items


def _joints(it: IterationRehearsal) -> Table:
    """Tracking error and torque per active joint."""
    e, p = it.export, it.played
    error = np.degrees(p.q - e.q)
    rows = []
    for j, name in enumerate(e.joint_names):
        peak, limit = np.abs(p.tau[:, j]).max(), it.effort[j]
        use = f"{100 * peak / limit:.0f} %" if 0 < limit < np.inf else "no limit"
        rows.append(
            [
                name,
                f"{np.sqrt(np.mean(error[:, j] ** 2)):.3f}",
                f"{np.abs(error[:, j]).max():.3f}",
                f"{peak:.2f}",
                f"{limit:g}" if 0 < limit < np.inf else "-",
                use + (" over" if 0 < limit < peak else ""),
            ]
        )
    return titled_table(
        f"iteration {it.iteration}: {e.time[-1]:.2f} s at speed {e.speed:g}",
        ["joint", "tracking RMS [deg]", "peak [deg]", "peak torque [N·m]", "limit [N·m]", "of limit"],
        rows,
    )


def _lines(it: IterationRehearsal, feedforward: bool) -> list[str]:
    """Contacts, the held joints' torques and a standing robot's balance."""
    p = it.played
    if p.drop is not None:  # a standing robot's only contact geometry is its soles'
        lines = ["contacts: the soles' only (a standing robot's other bodies have no contact geometry here)"]
    else:
        lines = [
            "contacts: "
            + (
                "; ".join(f"{a} with {b} at {t:.3f} s" for (a, b), t in sorted(p.contacts.items(), key=lambda x: x[1]))
                if p.contacts
                else "none"
            )
            + (f" (touching at rest, not counted: {', '.join(f'{a}-{b}' for a, b in p.at_rest)})" if p.at_rest else ""),
        ]
    if it.refused:
        lines.append(f"excite export refuses this speed (played here all the same): {it.refused}")
    for name, peak, limit in it.over_limit:
        lines.append(f"over its limit: {name} {peak:.2f} N·m against {limit:g} N·m")
    if p.drop is None:
        return lines
    if p.held_tau.size and it.held_effort.size:
        use = np.abs(p.held_tau).max(axis=0) / np.where(it.held_effort > 0, it.held_effort, np.inf)
        worst = int(np.argmax(use))
        lines.append(
            f"held joints: largest torque {100 * use[worst]:.0f} % of its limit "
            f"({it.held_names[worst]}, {np.abs(p.held_tau[:, worst]).max():.1f} N·m)"
        )
    lines.append(_balance("with the held joints' feed-forward" if feedforward else "PD alone", p, it.predicted))
    if it.alone is not None:
        lines.append(_balance("PD alone", it.alone, it.predicted))
    return lines


def _balance(stance: str, p: Played, predicted: np.ndarray | None) -> str:
    """One stance's centre of pressure, tilts and verdict."""
    gap = ""
    if predicted is not None:
        gap = f", RMS gap to excite's ZMP {1000 * np.sqrt(np.nanmean(np.sum((p.cop - predicted) ** 2, axis=1))):.1f} mm"
    return (
        f"{stance}: {'FALLS' if p.fell else 'stands'}, centre of pressure at least {1000 * p.margin.min():.1f} mm "
        f"inside the soles{gap}, sole tilt {p.sole_tilt.max():.2f}°, base tilt {p.root_tilt.max():.2f}°, "
        f"base {1000 * p.drop.max():.1f} mm lower"
    )
