"""Plots of docs/figures.md's measured tables, drawn from the tables themselves (so a plot and its
table never disagree): ``python docs/figure_plots.py [FOLDER]`` writes four PNGs into FOLDER
(default docs/images), each shown beside its table."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FIGURES = Path(__file__).resolve().parent / "figures.md"


def table(title: str, text: str | None = None) -> list[list[str]]:
    """The rows (cells as text, header first) of the first Markdown table after the paragraph that
    starts with ``**<title>``."""
    text = text or FIGURES.read_text()
    after = text[text.index(f"**{title}") :]
    lines = [line for line in after.splitlines() if line.startswith("|")]
    start = after.splitlines().index(lines[0])
    rows = []
    for line in after.splitlines()[start:]:
        if not line.startswith("|"):
            break
        if not re.fullmatch(r"\|(\s*-+\s*\|)+", line):
            rows.append([cell.strip() for cell in line.strip("|").split("|")])
    return rows


def number(cell: str) -> float:
    """The first number of a cell (``**3.12 %** (3.15 / …)`` → 3.12; ``133 345`` → 133345)."""
    return float(re.search(r"-?\d[\d ]*\.?\d*(?:e-?\d+)?", cell.replace("−", "-")).group().replace(" ", ""))


def _filled(rows: list[list[str]], column: int) -> list[list[str]]:
    """Rows with an empty cell in ``column`` given the value above (a table's grouped first column)."""
    last = ""
    for row in rows:
        last = row[column] = row[column] or last
    return rows


def sequential(folder: Path) -> Path:
    rows = _filled(table("Sequential generation on the G1 arms")[1:], 0)
    fig, ax = plt.subplots(figsize=(5, 3.2))
    labels = {
        "log_trace_inverse": "A-optimality (default; the parameters' expected error)",
        "log_cond": "log cond (the paper's criterion)",
    }
    for criterion in dict.fromkeys(r[0] for r in rows):
        mine = [r for r in rows if r[0] == criterion]
        name = re.sub(r"[`*]", "", criterion).split(" (")[0]
        ax.plot([number(r[1]) for r in mine], [number(r[3]) for r in mine], "o-", label=labels.get(name, name))
    ax.plot([1, 2, 3], [47.6, 35.7, 33.9], "k--", label="paper, HRP-4 (Table I, log cond)")
    ax.set(xlabel="iteration", ylabel="cond(C) stacked [1]", xticks=[1, 2, 3], title="G1 arms: cond(C) per iteration")
    ax.legend(fontsize=7, loc="lower right", bbox_to_anchor=(1.0, 0.1))
    return _save(fig, folder / "sequential_cond.png")


def random_against_optimized(folder: Path) -> Path:
    rows = table("Random feasible motions + greedy selection")[1:]
    fig, ax = plt.subplots(figsize=(5, 3.2))
    motions = [number(r[0]) for r in rows]
    ax.semilogy(motions, [number(r[2]) for r in rows], "s-", label="random + greedy (2 000 candidates)")
    ax.semilogy(motions, [number(r[4]) for r in rows], "o-", label="optimized")
    ax.set(xlabel="motions stacked", ylabel="cond(C)", xticks=motions, title="G1 arms: compare-random")
    ax.legend(fontsize=8)
    return _save(fig, folder / "random_against_optimized.png")


def criteria(folder: Path) -> Path:
    rows = _filled(table("Which criterion identifies best")[1:], 0)
    fig, axes = plt.subplots(1, 2, figsize=(8, 3.2))
    for ax, problem in zip(axes, dict.fromkeys(r[0] for r in rows)):
        mine = [r for r in rows if r[0] == problem and not r[1].startswith("random")]
        labels = [re.sub(r"[`*]", "", r[1]).split(" (")[0] for r in mine]
        ax.barh(labels, [number(r[5]) for r in mine], label="parameter error, mean of seeds 0-2")
        ax.invert_yaxis()
        ax.set(xlabel="parameter error [%]", title=problem)
        ax.tick_params(axis="y", labelsize=7)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle("Each criterion's trajectories identified in the loop (shorter is better)", fontsize=10)
    return _save(fig, folder / "criteria_in_the_loop.png")


def identification(folder: Path) -> Path:
    rows = table("Models that hold on runs the fit never saw")[1:]
    labels = [r[0].split(" (")[0] for r in rows]  # columns: data, rigid, least squares, consistent, reported
    fig, ax = plt.subplots(figsize=(6, 3.2))
    width, y = 0.4, range(len(rows))
    ax.barh([k - width / 2 for k in y], [number(r[1]) for r in rows], width, label="rigid body (URDF)")
    ax.barh([k + width / 2 for k in y], [number(r[4]) for r in rows], width, label="identified (reported)")
    ax.set_yticks(list(y), labels, fontsize=8)
    ax.invert_yaxis()
    ax.set(xlabel="relative validation torque error [%]", title="Panda: before and after identification")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.22), ncol=2)
    return _save(fig, folder / "identification_before_after.png")


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


PLOTS = (sequential, random_against_optimized, criteria, identification)


def main(folder: Path) -> list[Path]:
    """Every plot of :data:`PLOTS` into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    return [plot(folder) for plot in PLOTS]


if __name__ == "__main__":
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else FIGURES.parent / "images"):
        print(f"wrote {path}")
