"""The torque noise ``identify`` measured on the fit residual, as a table."""

from __future__ import annotations

from rich.table import Table

from excite_cli.console.tables import titled_table
from excite_cli.identification.fitting.noise_level import BLOCKS, CLEAR
from excite_cli.identification.reporting.report import Report


def noise_table(report: Report) -> list[Table]:
    """Per joint a [Nm] and ρ [%] of σ² = a² + (ρτ)² with their standard deviations, a's 95 % upper bound
    (what a next design takes for a) and which noise the data prefer; nothing when the fit data were too
    short to fit it."""
    if not report.noise_levels:
        return []
    rows = [
        (name, "no signal", "", "", "")
        if level is None
        else (
            name,
            f"{level.absolute:.3g} ± {level.absolute_std:.2g}",
            f"{level.absolute_upper:.3g}",
            f"{100 * level.relative:.3g} ± {100 * level.relative_std:.2g}",
            "growing with the torque" if level.preferred == "relative" else "absolute",
        )
        for name, level in zip(report.joints, report.noise_levels)
    ]
    return [
        titled_table(
            "Torque noise on the fit residual, σ² = a² + (ρ τ)², at the recording's own rate "
            f"(std: jackknife over {BLOCKS} blocks)",
            ("joint", "a [Nm]", "a, 95 % bound [Nm]", "ρ [%]", "the data prefer"),
            rows,
            f"growing with the torque where ρ is {CLEAR:g} std above zero; with this report as sequence.prior, "
            "optimize designs the next trajectory for this noise, a at its bound",
        )
    ]
