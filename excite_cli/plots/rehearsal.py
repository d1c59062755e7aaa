"""The rehearsal's picture: per iteration the tracking error over time and, for a standing robot, the
centre of pressure's path inside the support polygon beside excite's predicted zero-moment point."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from excite_cli.plots.figure import joint_colours, plt, save_figure
from excite_cli.rehearsal.report import Rehearsal


def plot_rehearsal(path: Path, r: Rehearsal) -> Path:
    """One row per iteration: the active joints' tracking error [deg] over time, and for a standing robot
    the centre of pressure [mm] inside the support polygon (with PD alone where played). Written to
    ``path`` (PNG).

    Raises:
        CannotWrite: the file cannot be written.
    """
    columns = 2 if r.standing else 1
    fig, axes = plt.subplots(
        len(r.iterations), columns, figsize=(7.5 * columns, 3.4 * len(r.iterations)), squeeze=False
    )
    for row, it in zip(axes, r.iterations):
        error = np.degrees(it.played.q - it.export.q)
        for j, (name, colour) in enumerate(zip(it.export.joint_names, joint_colours(len(it.export.joint_names)))):
            row[0].plot(it.played.time, error[:, j], color=colour, lw=0.8, label=name)
        row[0].set(xlabel="time [s]", ylabel="tracking error [deg]", title=f"iteration {it.iteration}")
        row[0].legend(fontsize=5, loc="center left", bbox_to_anchor=(1.0, 0.5))
        if r.standing:
            _support(row[1], it)
    fig.tight_layout()
    return save_figure(fig, path, 120)


def _support(ax, it) -> None:
    """The support polygon, the centre of pressure's paths and the predicted ZMP [mm]."""
    corners = 1000 * it.played.polygon.vertices
    closed = np.vstack([corners, corners[:1]])
    ax.plot(closed[:, 0], closed[:, 1], "k-", lw=1.0, label="support polygon (MuJoCo's contacts)")
    if it.predicted is not None:
        ax.plot(*(1000 * it.predicted.T), color="0.6", lw=0.8, label="excite's zero-moment point")
    ax.plot(*(1000 * it.played.cop.T), color="C0", lw=0.8, label="centre of pressure")
    if it.alone is not None:
        ax.plot(*(1000 * it.alone.cop.T), color="C3", lw=0.8, label="centre of pressure, PD alone")
    ax.set(xlabel="x [mm]", ylabel="y [mm]", aspect="equal", title=f"iteration {it.iteration}: balance")
    ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.0, 0.5))
