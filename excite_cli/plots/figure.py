"""A figure written as a PNG file whole or not at all (rendered in memory, then :func:`atomic_bytes`)."""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from excite_cli.atomic import MARK, atomic_bytes  # noqa: E402


def save_figure(fig: plt.Figure, path: Path, dpi: int) -> Path:
    """``fig`` as a PNG at ``path`` (``dpi`` dots per inch), then closed; ``path`` returned.

    Raises:
        CannotWrite: the file cannot be written (a full disk, a folder without write permission).
    """
    buffer = io.BytesIO()
    try:
        fig.savefig(buffer, format="png", dpi=dpi, metadata={"Software": MARK})
    finally:
        plt.close(fig)
    return atomic_bytes(path, buffer.getvalue(), "output")


def joint_colours(count: int) -> list:
    """``count`` distinguishable colours (tab10, then tab20's light shades; 20 before repeating)."""
    palette = list(plt.get_cmap("tab10").colors) + list(plt.get_cmap("tab20").colors[1::2])
    return [palette[j % len(palette)] for j in range(count)]
