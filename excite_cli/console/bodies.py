"""What ``identify`` prints of its physically consistent fit: each body beside the URDF's, the rotors
and the payloads held apart from the bodies."""

from __future__ import annotations

import numpy as np
from rich.table import Table

from excite_cli.console.tables import titled_table
from excite_cli.dynamics.robot import Robot
from excite_cli.identification.fitting.bodies import body_properties, pseudo_inertia
from excite_cli.identification.fitting.physical import ConsistentFit


def consistent_bodies(fit: ConsistentFit, robot: Robot) -> Table:
    """Identified (physically consistent) bodies beside the URDF's, the active constraints, the rotors and
    the payloads."""
    urdf = robot.urdf_parameters()
    payloads, rotors = zip(fit.payload_bodies, fit.payloads), zip(fit.rotor_joints, fit.rotors, fit.own_columns)
    vector = lambda v: " ".join(f"{x:+.3f}" for x in v)  # noqa: E731
    where = lambda p: f" at {vector(p[1:4] / p[0])} m" if p[0] >= 1e-3 else ""  # noqa: E731  (no centre below 1 g)
    rows = []
    for i, name in enumerate(robot.body_names):
        m, c, _, moments = body_properties(fit.standard[10 * i : 10 * i + 10])
        um, uc, _, umoments = body_properties(urdf[10 * i : 10 * i + 10])
        rows.append(
            (
                name,
                f"{m:.3f} / {um:.3f}",
                f"{vector(c)} / {vector(uc)}",
                f"{' '.join(f'{x:.2e}' for x in moments)} / {' '.join(f'{x:.2e}' for x in umoments)}",
                f"{fit.min_eigenvalues[i]:.1e}",
            )
        )
    plain = [
        (name, body_properties(fit.unconstrained[10 * i : 10 * i + 10])[0])
        for i, name in enumerate(robot.body_names)
        if np.linalg.eigvalsh(pseudo_inertia(fit.unconstrained[10 * i : 10 * i + 10]))[0] <= 0.0
    ]
    return titled_table(
        f"Physically consistent bodies (identified / URDF), solver {fit.status}",
        ("body", "mass [kg]", "CoM [m]", "principal moments about the CoM [kg m²]", "λmin(J)"),
        rows,
        "active: "
        + (", ".join(fit.active) or "none")
        + "\nplain least squares (same regularization) is not physical for: "
        + (", ".join(f"{name} (mass {m:.3f} kg)" for name, m in plain) or "none")
        + "\nrotor inertias held apart from the bodies [kg m²] (regrouped: in the base parameters with a link's): "
        + (", ".join(f"{j} {a:.4g}{'' if o else ' regrouped'}" for j, a, o in rotors) or "none")
        + "\npayloads held apart on the last bodies (in their masses above): "
        + (", ".join(f"{b} {p[0]:.3f} kg{where(p)}" for b, p in payloads) or "none"),
    )
