"""The constraint tracks of an optimize result, one row of panels per track a constraint gives
(:meth:`~excite_cli.constraints.constraint.Constraint.track`): the centre of mass against its region
(Eq. 52), the zero-moment point in the support polygon, the smallest capsule distance (Eq. 53) and
the smallest distance to the world, and each joint's torque against its limit."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from excite_cli.constraints.support import SupportPolygon  # noqa: E402
from excite_cli.plots.figure import joint_colours, save_figure  # noqa: E402
from excite_cli.search.sequence import IterationResult  # noqa: E402


@dataclass(frozen=True)
class Drawn:
    """What the constraints draw beside their tracks (:meth:`Constraint.drawn`) and the joints' names.

    Attributes:
        centre: (2,) CoM region centre [m]; radius [m] or polygon (K, 2) relative to it [m].
        margin: capsule safety margin [m].
        support: the support polygon the ZMP keeps ``zmp_margin`` [m] inside.
        joints: (n,) the active joints' names, for the torque panel's legend.
    """

    centre: np.ndarray | None = None
    radius: float | None = None
    polygon: np.ndarray | None = None
    margin: float | None = None
    support: SupportPolygon | None = None
    zmp_margin: float = 0.0
    joints: Sequence[str] = ()


def _com(ax, r: IterationResult, d: Drawn) -> None:
    if d.centre is None:
        return
    xy = (r.tracks["com_xy"] - d.centre) * 100
    ax.plot(xy[:, 0], xy[:, 1], linewidth=0.8, label="CoM track")
    if d.radius is not None:
        ax.add_patch(plt.Circle((0, 0), d.radius * 100, fill=False, color="r", label="region"))
    if d.polygon is not None:
        ax.add_patch(plt.Polygon(d.polygon * 100, fill=False, color="r", label="region"))
    ax.set(aspect="equal", xlabel="x − centre [cm]", ylabel="y − centre [cm]")
    ax.legend(fontsize=7)


def _zmp(ax, r: IterationResult, d: Drawn) -> None:
    if d.support is None:
        return
    ax.plot(*(r.tracks["zmp_xy"] * 100).T, linewidth=0.8, label="ZMP track")
    ax.add_patch(plt.Polygon(d.support.vertices * 100, fill=False, color="k", label="support polygon"))
    inner = d.support.shrunk(d.zmp_margin) * 100
    ax.add_patch(plt.Polygon(inner, fill=False, color="r", linestyle="--", label=f"{d.zmp_margin * 1000:g} mm in"))
    ax.set(aspect="equal", xlabel="x [cm]", ylabel="y [cm]")
    ax.legend(fontsize=7)


def _capsules(ax, r: IterationResult, d: Drawn) -> None:
    ax.plot(r.time, r.tracks["min_capsule_distance"] * 100, linewidth=0.8, label="smallest distance")
    if d.margin is not None:
        ax.axhline(d.margin * 100, color="r", linestyle="--", label="margin")
    ax.set(xlabel="time [s]", ylabel="capsule distance [cm]")
    ax.legend(fontsize=7)


def _world(ax, r: IterationResult, d: Drawn) -> None:
    ax.plot(r.time, r.tracks["min_world_distance"] * 100, linewidth=0.8, label="smallest distance to the world")
    ax.set(xlabel="time [s]", ylabel="distance to the world [cm]")
    ax.legend(fontsize=7)


def _torques(ax, r: IterationResult, d: Drawn, last: bool) -> None:
    use = r.tracks["torque_use"]
    names = list(d.joints) or [f"joint {j + 1}" for j in range(use.shape[1])]
    for j, colour in enumerate(joint_colours(use.shape[1])):
        ax.plot(r.time, use[:, j], linewidth=0.7, color=colour, label=names[j])
    ax.axhline(1.0, color="r", linestyle="--", label="limit")
    ax.set(xlabel="time [s]", ylabel="|τ| / τ_max per joint")
    if last:  # the joints named once, beside the last iteration
        ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1.0))


#: Each track a constraint gives (its name in the result file) and the panel that draws it, in the
#: figure's order; a panel is told whether its column is the last.
PANELS: dict[str, Callable] = {
    "com_xy": lambda ax, r, d, last: _com(ax, r, d),
    "zmp_xy": lambda ax, r, d, last: _zmp(ax, r, d),
    "min_capsule_distance": lambda ax, r, d, last: _capsules(ax, r, d),
    "min_world_distance": lambda ax, r, d, last: _world(ax, r, d),
    "torque_use": _torques,
}


def plot_constraint_tracks(path: Path, results: Sequence[IterationResult], drawn: Drawn) -> Path:
    """Per iteration (a column), a panel per track the run's constraints give (:data:`PANELS`), with
    what ``drawn`` says they keep to; written to ``path`` (PNG).

    Raises:
        ExciteError: ``path`` cannot be written (:func:`~excite_cli.plots.figure.save_figure`).
    """
    kinds = [k for k in PANELS if any(k in r.tracks for r in results)]
    fig, axes = plt.subplots(len(kinds), len(results), figsize=(4.2 * len(results), 3.7 * len(kinds)), squeeze=False)
    for col, r in enumerate(results):
        axes[0, col].set_title(f"iteration {r.index}")
        for ax, kind in zip(axes[:, col], kinds):
            ax.grid(alpha=0.3)
            if kind in r.tracks:
                PANELS[kind](ax, r, drawn, col == len(results) - 1)
    fig.tight_layout()
    return save_figure(fig, path, 110)
