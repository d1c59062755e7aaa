"""PNG figures of a sequential generation: joint trajectories and the condition-number table."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import numpy as np  # noqa: E402

from excite_cli.sequence import IterationResult  # noqa: E402


def plot_trajectories(path: Path, joint_names: Sequence[str], results: Sequence[IterationResult]) -> Path:
    """q, q̇, q̈ of every iteration over time, one column per iteration; written to ``path`` (PNG)."""
    fig, axes = plt.subplots(3, len(results), figsize=(4.5 * len(results), 8), sharex=True, squeeze=False)
    for col, r in enumerate(results):
        for row, (name, unit) in enumerate((("q", "rad"), ("qd", "rad/s"), ("qdd", "rad/s²"))):
            ax = axes[row, col]
            ax.plot(r.time, getattr(r, name), linewidth=0.8)
            ax.set_ylabel(f"{name} [{unit}]")
            ax.grid(alpha=0.3)
        axes[0, col].set_title(f"iteration {r.index}: cond {r.cond_own:.1f}")
        axes[-1, col].set_xlabel("time [s]")
    axes[0, -1].legend(joint_names, fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_condition_numbers(path: Path, results: Sequence[IterationResult]) -> Path:
    """cond(C⁽ⁱ⁾) and cond(C) per iteration (the paper's Table I as a chart); written to ``path`` (PNG)."""
    fig, ax = plt.subplots(figsize=(5, 3.5))
    k = [r.index for r in results]
    ax.plot(k, [r.cond_own for r in results], "o-", label="cond(C⁽ⁱ⁾) own")
    ax.plot(k, [r.cond_stacked for r in results], "s-", label="cond(C) stacked")
    ax.set_xlabel("iteration")
    ax.set_ylabel("condition number")
    ax.set_xticks(k)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_constraint_tracks(path: Path, results: Sequence[IterationResult], centre=None, radius: float | None = None,
                           polygon=None, margin: float | None = None) -> Path:
    """Per iteration: the CoM ground track against its region (Eq. 52) and the smallest capsule
    distance over time against the margin (Eq. 53), in cm; written to ``path`` (PNG).

    Args:
        centre: (2,) region centre [m]; radius [m] or polygon (K, 2) relative to it [m].
        margin: capsule safety margin [m].
    """
    fig, axes = plt.subplots(2, len(results), figsize=(4.2 * len(results), 7.5), squeeze=False)
    for col, r in enumerate(results):
        ax = axes[0, col]
        if "com_xy" in r.tracks and centre is not None:
            xy = (r.tracks["com_xy"] - centre) * 100
            ax.plot(xy[:, 0], xy[:, 1], linewidth=0.8, label="CoM track")
            if radius is not None:
                ax.add_patch(plt.Circle((0, 0), radius * 100, fill=False, color="r", label="region"))
            if polygon is not None:
                ax.add_patch(plt.Polygon(polygon * 100, fill=False, color="r", label="region"))
            ax.set_aspect("equal")
            ax.set_xlabel("x − centre [cm]")
            ax.set_ylabel("y − centre [cm]")
            ax.legend(fontsize=7)
        ax.set_title(f"iteration {r.index}")
        ax = axes[1, col]
        if "min_capsule_distance" in r.tracks:
            ax.plot(r.time, r.tracks["min_capsule_distance"] * 100, linewidth=0.8, label="smallest distance")
            if margin is not None:
                ax.axhline(margin * 100, color="r", linestyle="--", label="margin")
            ax.set_xlabel("time [s]")
            ax.set_ylabel("capsule distance [cm]")
            ax.legend(fontsize=7)
        for a in axes[:, col]:
            a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_comparison(path: Path, random_table, optimized_table) -> Path:
    """Bars of cond(C⁽ⁱ⁾) and cond(C) per motion index, random selection (Table II) beside the
    optimized trajectories (Table I); log scale; written to ``path`` (PNG)."""
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.8))
    for ax, column, title in zip(axes, ("cond_own", "cond_stacked"), ("cond(C⁽ⁱ⁾)", "cond(C) stacked")):
        k = np.asarray(random_table["iteration"])
        ax.bar(k - 0.2, random_table[column], width=0.4, label="random + selection")
        if optimized_table is not None:
            ax.bar(np.asarray(optimized_table["iteration"]) + 0.2, optimized_table[column], width=0.4, label="optimized")
        ax.set_yscale("log")
        ax.set_xticks(k)
        ax.set_xlabel("motion index")
        ax.set_title(title)
        ax.grid(alpha=0.3, axis="y")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_identification(path: Path, report) -> Path:
    """Per joint, on validation data: measured torque with the rigid-body and the final prediction,
    and the residuals before and after; written to ``path`` (PNG)."""
    n = len(report.joints)
    data = report.validation
    first = data.run == data.run[0]
    t = data.time[first].copy()
    # break the lines between held-out time blocks
    t[1:][np.diff(t) > 2 * np.median(np.diff(t))] = np.nan
    measured = data.tau.reshape(-1, n)
    fig, axes = plt.subplots(n, 2, figsize=(12, 1.9 * n), sharex=True, squeeze=False)
    for j, name in enumerate(report.joints):
        ax = axes[j, 0]
        ax.plot(t, measured[first, j], "k", linewidth=0.8, label="measured")
        ax.plot(t, report.predicted_before[first, j], linewidth=0.7, label="rigid body")
        ax.plot(t, report.predicted_after[first, j], linewidth=0.7, label="with effects")
        ax.set_ylabel(f"{name}\nτ [Nm]", fontsize=7)
        ax = axes[j, 1]
        ax.plot(t, measured[first, j] - report.predicted_before[first, j], linewidth=0.7,
                label=f"before: RMS {report.rms_before[j]:.3f} Nm")
        ax.plot(t, measured[first, j] - report.predicted_after[first, j], linewidth=0.7,
                label=f"after: RMS {report.rms_after[j]:.3f} Nm")
        ax.set_ylabel("residual [Nm]", fontsize=7)
        ax.legend(fontsize=6, loc="upper right")
        for a in axes[j]:
            a.grid(alpha=0.3)
            a.tick_params(labelsize=7)
    axes[0, 0].legend(fontsize=6, loc="upper right")
    axes[0, 0].set_title("validation data (first held-out run or blocks)", fontsize=9)
    axes[0, 1].set_title("residual before / after the effects", fontsize=9)
    for a in axes[-1]:
        a.set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
