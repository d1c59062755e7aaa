"""The figure of ``compare-random``: random feasible motions with greedy selection (the paper's Table II)
beside the optimized trajectories (Table I)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from excite_cli.plots.figure import save_figure  # noqa: E402


def plot_comparison(path: Path, random_table, optimized_table) -> Path:
    """Bars of cond(C⁽ⁱ⁾) and cond(C) per motion index, random selection (Table II) beside the
    optimized trajectories (Table I); log scale; written to ``path`` (PNG)."""
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.8))
    for ax, column, title in zip(axes, ("cond_own", "cond_stacked"), ("cond(C⁽ⁱ⁾)", "cond(C) stacked")):
        k = np.asarray(random_table["iteration"])
        ax.bar(k - 0.2, random_table[column], width=0.4, label="random + selection")
        if optimized_table is not None:
            ax.bar(
                np.asarray(optimized_table["iteration"]) + 0.2, optimized_table[column], width=0.4, label="optimized"
            )
        ax.set_yscale("log")
        ax.set_xticks(k)
        ax.set_xlabel("motion index")
        ax.set_title(title)
        ax.grid(alpha=0.3, axis="y")
        ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path, 110)
