"""Figures of ``identify``: the validation residuals, and the selection's ladder and steps (PNG,
matplotlib)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from excite_cli.identification.choice.admission import Admission  # noqa: E402
from excite_cli.identification.reporting.report import Report  # noqa: E402
from excite_cli.plots.figure import save_figure  # noqa: E402


def _end_to_end(time: np.ndarray, run: np.ndarray) -> np.ndarray:
    """(N,) time [s] of samples from several runs laid end to end, NaN at every gap (between runs
    and between held-out blocks of a run), so plotted lines break there."""
    out = np.empty(time.size)
    offset, step = 0.0, float(np.median(np.diff(time))) if time.size > 1 else 1.0
    for r in np.unique(run):
        rows = np.flatnonzero(run == r)
        out[rows] = time[rows] - time[rows[0]] + offset
        offset = out[rows[-1]] + 20 * step
    out[1:][(np.diff(time) > 2 * step) | (np.diff(run) != 0)] = np.nan
    return out


def plot_identification(path: Path, report: Report) -> Path:
    """Per joint, on all validation data (runs laid end to end, a gap between runs and between
    held-out time blocks): measured torque with the rigid-body and the final prediction, and the
    residuals before and after; written to ``path`` (PNG)."""
    n = len(report.joints)
    data = report.validation
    t = _end_to_end(data.time, data.run)
    measured = data.tau.reshape(-1, n)
    fig, axes = plt.subplots(n, 2, figsize=(12, 1.9 * n), sharex=True, squeeze=False)
    for j, name in enumerate(report.joints):
        ax = axes[j, 0]
        ax.plot(t, measured[:, j], "k", linewidth=0.8, label="measured")
        ax.plot(t, report.predicted_before[:, j], linewidth=0.7, label="rigid body")
        ax.plot(t, report.predicted_after[:, j], linewidth=0.7, label="with effects")
        ax.set_ylabel(f"{name}\nτ [Nm]", fontsize=7)
        ax = axes[j, 1]
        ax.plot(
            t,
            measured[:, j] - report.predicted_before[:, j],
            linewidth=0.7,
            label=f"before: RMS {report.rms_before[j]:.3f} Nm",
        )
        ax.plot(
            t,
            measured[:, j] - report.predicted_after[:, j],
            linewidth=0.7,
            label=f"after: RMS {report.rms_after[j]:.3f} Nm",
        )
        ax.set_ylabel("residual [Nm]", fontsize=7)
        ax.legend(fontsize=6, loc="upper right")
        for a in axes[j]:
            a.grid(alpha=0.3)
            a.tick_params(labelsize=7)
    axes[0, 0].legend(fontsize=6, loc="upper right")
    axes[0, 0].set_title("validation data (every held-out run and block, laid end to end)", fontsize=9)
    axes[0, 1].set_title("residual before / after the effects", fontsize=9)
    for a in axes[-1]:
        a.set_xlabel("time [s]")
    fig.tight_layout()
    return save_figure(fig, path, 100)


def plot_ladder(path: Path, report: Report) -> Path:
    """Two panels, written to ``path`` (PNG): the mean relative error after each step of the kept
    search (bars: validation data; dots: cross-validated on the fit data, what the search minimizes),
    and every move tried at each step with its gain (cut of the cross-validated error [%]), the one
    taken marked, the ``min_improvement`` line beside them (or, under the paired test over folds, the
    margin each move taken passed)."""
    labels, cv, val = zip(*report.ladder)
    sel = report.selection
    fig, (top, bottom) = plt.subplots(
        2, 1, figsize=(max(6.0, 0.42 * len(labels) + 2.5), 7.5), gridspec_kw={"height_ratios": [3, 2]}
    )
    x = np.arange(len(labels))
    top.bar(x[:1], val[:1], color="0.55", label="rigid body (URDF), validation")
    top.bar(x[1:], val[1:], color="C0", label="after each step, validation (never seen by fit or selection)")
    top.plot(
        x,
        cv,
        "o-",
        color="C3",
        markersize=4,
        label=f"cross-validated ({sel.folds} folds of the fit data by {sel.folds_by})",
    )
    top.set_xticks(x, labels, rotation=60, ha="right", fontsize=7)
    top.set_ylabel("mean relative error [%]")
    top.set_title("what each effect bought", fontsize=9)
    top.legend(fontsize=7)
    top.grid(axis="y", alpha=0.3)
    for k, step in enumerate(sel.steps, start=1):
        gains = np.array([step.gain_of(v) for _, _, v in step.tried])
        bottom.plot(
            np.full(gains.size, k) + np.linspace(-0.25, 0.25, gains.size), gains, ".", color="0.6", markersize=3
        )
        bottom.plot(k, step.gain, "*", color="C3", markersize=9)
    if sel.admission is Admission.PRICED:
        bottom.axhline(
            100.0 * (1.0 - 1.0 / (1.0 + sel.min_improvement)),
            color="k",
            linewidth=0.8,
            linestyle="--",
            label="min_improvement",
        )
    else:  # each move taken passed the paired test over the folds: its margin
        margins = [step.fold_margin for step in sel.steps]  # NaN for a removal of an estimate not clear of zero
        bottom.plot(np.arange(1, len(margins) + 1), margins, "_", color="k", markersize=12, label="paired-test margin")
    bottom.set_xlabel("step of the search (★ the move taken, dots every move tried)")
    bottom.set_ylabel("gain [%]")
    bottom.set_ylim(bottom=max(-20.0, bottom.get_ylim()[0]))
    bottom.legend(fontsize=7)
    bottom.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path, 110)
