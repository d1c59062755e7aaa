"""PNG figures of a sequential generation: joint trajectories and the condition-number table."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

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
