"""The PNG figures of an optimize result: joint trajectories with their limits, the condition-number table,
posture strips, and the constraint tracks (:mod:`~excite_cli.plots.tracks`)."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from excite_cli.collision.world import WorldShape, world_shapes  # noqa: E402
from excite_cli.design.excitation import Excitation  # noqa: E402
from excite_cli.plots.figure import joint_colours, save_figure  # noqa: E402
from excite_cli.plots.shapes import draw_shape, stadium  # noqa: E402
from excite_cli.plots.skeleton import capsule_segments, skeleton  # noqa: E402
from excite_cli.plots.tracks import Drawn, plot_constraint_tracks  # noqa: E402
from excite_cli.search.sequence import IterationResult  # noqa: E402


def figure_paths(target: Path) -> list[Path]:
    """The figures of an ``optimize`` result at ``target``: ``<stem>_trajectories.png``, ``_cond.png``,
    ``_postures.png`` and, with balance or collision constraints, ``_constraints.png``."""
    stem = Path(target).with_suffix("")
    return [stem.with_name(stem.name + f"_{name}.png") for name in ("trajectories", "cond", "postures", "constraints")]


def plot_result(target: Path, excitation: Excitation, results: Sequence[IterationResult]) -> list[Path]:
    """The PNG figures of an ``optimize`` result beside ``target`` (:func:`figure_paths`)."""
    trajectories, cond, postures, tracks = figure_paths(target)
    drawn = {key: value for c in excitation.constraints for key, value in c.drawn().items()}
    capsules = next((c.capsules for c in excitation.constraints if len(c.capsules)), [])
    limits = excitation.limits
    plots = [
        plot_trajectories(
            trajectories,
            excitation.robot.joint_names,
            results,
            limits.lower,
            limits.upper,
        ),
        plot_condition_numbers(cond, results),
        plot_postures(
            postures,
            results,
            lambda q: (skeleton(excitation.robot, q), capsule_segments(excitation.robot, capsules, q)),
            [c.radius for c in capsules],
            excitation.home,
            world_shapes(excitation.spec.constraints.environment),  # those out of reach too
        ),
    ]
    if any(r.tracks for r in results):
        plots.append(plot_constraint_tracks(tracks, results, Drawn(**drawn, joints=excitation.robot.joint_names)))
    return plots


def plot_trajectories(
    path: Path,
    joint_names: Sequence[str],
    results: Sequence[IterationResult],
    lower: np.ndarray | None = None,
    upper: np.ndarray | None = None,
) -> Path:
    """q, q̇, q̈ of every iteration over time, one column per iteration, each joint in its own colour,
    with the joint limits (Eq. 51) as dashed lines in the joint's colour; written to ``path`` (PNG).

    Args:
        lower, upper: (3, n) bounds of q [rad], q̇ [rad/s], q̈ [rad/s²], or None.
    """
    colours = joint_colours(len(joint_names))
    fig, axes = plt.subplots(3, len(results), figsize=(4.5 * len(results) + 2.5, 8), sharex=True, squeeze=False)
    for col, r in enumerate(results):
        for row, (name, unit) in enumerate((("q", "rad"), ("qd", "rad/s"), ("qdd", "rad/s²"))):
            ax = axes[row, col]
            for j, colour in enumerate(colours):
                ax.plot(r.time, getattr(r, name)[:, j], color=colour, linewidth=0.8, label=joint_names[j])
                if lower is not None and upper is not None:
                    for bound in (lower[row, j], upper[row, j]):
                        ax.axhline(bound, color=colour, linestyle="--", linewidth=0.6, alpha=0.6)
            ax.set_ylabel(f"{name} [{unit}]")
            ax.grid(alpha=0.3)
        axes[0, col].set_title(f"iteration {r.index}: cond {r.cond_own:.1f}")
        axes[-1, col].set_xlabel("time [s]")
    handles, labels = axes[0, -1].get_legend_handles_labels()
    handles.append(plt.Line2D([], [], color="grey", linestyle="--", linewidth=0.8))
    labels.append("limits (dashed)")
    axes[0, -1].legend(handles, labels, fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    return save_figure(fig, path, 110)


def plot_condition_numbers(path: Path, results: Sequence[IterationResult]) -> Path:
    """cond(C⁽ⁱ⁾) and cond(C) per iteration (the paper's Table I as a chart, log axis); written to
    ``path`` (PNG)."""
    fig, ax = plt.subplots(figsize=(5, 3.5))
    k = [r.index for r in results]
    ax.plot(k, [r.cond_own for r in results], "o-", label="cond(C⁽ⁱ⁾) own")
    ax.plot(k, [r.cond_stacked for r in results], "s-", label="cond(C) stacked")
    for r in results:
        ax.annotate(
            f"{r.cond_stacked:.1f}", (r.index, r.cond_stacked), textcoords="offset points", xytext=(4, -10), fontsize=7
        )
    ax.set_yscale("log")
    ax.margins(x=0.12)
    ax.set_xlabel("iteration")
    ax.set_ylabel("condition number (log)")
    ax.set_xticks(k)
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    fig.tight_layout()
    return save_figure(fig, path, 110)


def plot_postures(
    path: Path,
    results: Sequence[IterationResult],
    draw,
    radii: Sequence[float],
    home: np.ndarray,
    shapes: Sequence[WorldShape] = (),
    columns: int = 6,
) -> Path:
    """A strip of postures over one period per iteration, front view (from +x, the robot's left on the
    right) and side view (from −y, forward to the right), like the paper's Fig. 2; the home posture
    in grey behind every one. Written to ``path`` (PNG).

    Args:
        draw: ``draw(q)`` → (skeleton (L, 2, 3), capsule segments (C, 2, 3)) [m] at the posture q (n,) [rad].
        radii: (C,) capsule radii [m].
        home: (n,) home posture [rad].
        shapes: world shapes, drawn in grey (a half-space as its plane's trace, filled on the far side).
        columns: postures per iteration, at t = kT/columns.
    """
    views = (("front", 1, -1.0), ("side", 0, 1.0))  # horizontal world axis, its sign
    home_bones, _ = draw(home)
    picks = [np.linspace(0, len(r.time) - 1, columns, endpoint=False).astype(int) for r in results]
    poses = [[draw(r.q[t]) for t in ts] for r, ts in zip(results, picks)]
    points = np.concatenate([home_bones.reshape(-1, 3)] + [b.reshape(-1, 3) for row in poses for b, _ in row])
    pad = max(radii, default=0.0) + 0.05
    fig, axes = plt.subplots(2 * len(results), columns, figsize=(2.2 * columns, 2.4 * 2 * len(results)), squeeze=False)
    for i, r in enumerate(results):
        for c, (bones, capsules) in enumerate(poses[i]):
            t = r.time[picks[i][c]]
            for v, (view, axis, sign) in enumerate(views):
                ax = axes[2 * i + v, c]
                ax.add_collection(LineCollection(_in_view(home_bones, axis, sign), colors="0.8", linewidths=1.0))
                outlines = [stadium(a, b, radius) for (a, b), radius in zip(_in_view(capsules, axis, sign), radii)]
                ax.add_collection(PolyCollection(outlines, facecolors="tab:blue", alpha=0.15, linewidths=0))
                segments = _in_view(bones, axis, sign)
                ax.add_collection(LineCollection(segments, colors="k", linewidths=1.2))
                ends = segments.reshape(-1, 2)
                ax.plot(ends[:, 0], ends[:, 1], "o", color="k", markersize=1.5)
                horizontal = sign * points[:, axis]
                ax.set_xlim(horizontal.min() - pad, horizontal.max() + pad)
                ax.set_ylim(points[:, 2].min() - pad, points[:, 2].max() + pad)
                for shape in shapes:
                    draw_shape(ax, shape, axis, sign)
                ax.set_aspect("equal")
                ax.tick_params(labelsize=5, labelleft=c == 0, labelbottom=True)
                ax.set_xlabel(("y" if axis == 1 else "x") + " [m]", fontsize=6)
                if c == 0:
                    ax.set_ylabel("z [m]", fontsize=6)
                ax.set_title(f"iteration {r.index}, {view}, t = {t:.1f} s", fontsize=7)
    fig.legend(
        handles=[
            Line2D([], [], color="k", marker="o", markersize=2, linewidth=1.2, label="links (joint to joint)"),
            Patch(facecolor="tab:blue", alpha=0.15, label="collision capsules"),
            Line2D([], [], color="0.8", linewidth=1.0, label="home posture"),
        ]
        + ([Patch(facecolor="0.8", label="world shapes")] if shapes else []),
        loc="lower center",
        ncol=4,
        fontsize=7,
    )
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    return save_figure(fig, path, 100)


def _in_view(segments: np.ndarray, axis: int, sign: float) -> np.ndarray:
    """3-D segments (S, 2, 3) [m] in a view whose horizontal is world axis ``axis`` times ``sign``
    and vertical z: (S, 2, 2)."""
    segments = np.asarray(segments, dtype=float).reshape(-1, 2, 3)
    return np.stack([sign * segments[..., axis], segments[..., 2]], axis=-1)
