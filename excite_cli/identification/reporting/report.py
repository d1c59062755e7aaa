"""The identify report: what ``excite identify`` found, as one typed record that the report file,
the printed tables, the figures and ``--urdf-out`` read."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from excite_cli.identification.choice.fit_choice import FitChoice
from excite_cli.identification.choice.selection import Selection
from excite_cli.identification.effects import Term, coefficient_names
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import torque_errors
from excite_cli.identification.fitting.physical import ConsistentFit


@dataclass
class Report:
    """What ``identify`` found.

    Attributes:
        joints: (n,) active joint names.
        base_names: (b,) base-parameter names.
        selection: chosen effects, the least-squares fits, the search's steps.
        fit_choice: the fits compared by cross-validation, the chosen one, the consistent fit.
        rms_before, rms_after: (n,) validation torque RMS error [Nm], rigid body only (least squares)
            / the chosen fit with effects.
        rms_torque: (n,) RMS of the measured validation torques [Nm].
        rms_least_squares, rms_consistent: (n,) validation torque RMS error [Nm] of the least-squares
            fit with effects and of the consistent fit (None without one).
        validation: the validation samples; predicted_before, predicted_after: (N, n) [Nm] on them.
        cutoff: low-pass cut-off of every run [Hz]; cutoff_source: how it was chosen, in words.
        fit_samples, validation_samples: instants used for fitting / validation.
        dropped: (file, rows) left out as unusable, per run with ``data.bad_rows: drop``.
        run_names: (runs,) each configured run's label (file and crop), indexed by ``Dataset.run``.
        offset_runs: the runs whose offsets the fit has (one column each), as labels.
        ladder: (step, CV error on the fit data [%], mean relative validation error [%]) for the
            rigid body, the search's start and after each step of the kept search (least squares),
            then the consistent fit when it is the reported one.
        q_range: (n, 2) [rad] each joint's q range over the fit data; the position-dependent
            effects hold their value at its ends outside it (None: no position effect among the
            candidates, or ``position_guard`` off).
        warnings: what the user should know, in words (a URDF inertia kept as a reference only, a
            torque channel without signal).
    """

    joints: list[str]
    base_names: list[str]
    selection: Selection
    fit_choice: FitChoice
    rms_before: np.ndarray
    rms_after: np.ndarray
    rms_torque: np.ndarray
    rms_least_squares: np.ndarray
    rms_consistent: np.ndarray | None
    validation: Dataset
    predicted_before: np.ndarray
    predicted_after: np.ndarray
    cutoff: float
    cutoff_source: str
    fit_samples: int
    validation_samples: int
    dropped: list[tuple[str, int]] = field(default_factory=list)
    run_names: list[str] = field(default_factory=list)
    offset_runs: list[str] = field(default_factory=list)
    ladder: list[tuple[str, float, float]] = field(default_factory=list)
    q_range: np.ndarray | None = None
    warnings: list[str] = field(default_factory=list)

    @property
    def worse_than_rigid_body(self) -> np.ndarray:
        """(n,) the joints whose validation error ends above the rigid body's."""
        return self.rms_after > self.rms_before

    @property
    def consistent(self) -> ConsistentFit | None:
        """The physically consistent fit (chosen or beside least squares), or None."""
        return self.fit_choice.consistent

    @property
    def cv_error(self) -> float:
        """The reported model's CV error [%] (NaN: a consistent fit that was the only candidate)."""
        choice = self.fit_choice
        return float(choice.cv_error[choice.chosen]) if choice.is_consistent else self.selection.cv_error

    @property
    def relative_before(self) -> np.ndarray:
        """(n,) RMS error / RMS torque [%] before."""
        return 100.0 * self.rms_before / self.rms_torque

    @property
    def relative_after(self) -> np.ndarray:
        """(n,) RMS error / RMS torque [%] after."""
        return 100.0 * self.rms_after / self.rms_torque

    def per_run(self) -> list[tuple[str, int, np.ndarray, np.ndarray, np.ndarray]]:
        """(run name, instants, RMS error before (n,) [Nm], after (n,) [Nm], RMS torque (n,) [Nm]) of
        each validation run."""
        measured = self.validation.tau.reshape(-1, len(self.joints))
        out = []
        for r in np.unique(self.validation.run):
            rows = self.validation.run == r
            (before, torque, _), (after, _, _) = (
                torque_errors(measured[rows], p[rows]) for p in (self.predicted_before, self.predicted_after)
            )
            out.append(
                (self.run_names[r] if r < len(self.run_names) else str(r), int(rows.sum()), before, after, torque)
            )
        return out

    @property
    def relative_consistent(self) -> np.ndarray | None:
        """(n,) RMS error / RMS torque [%] of the physically consistent fit, or None."""
        return None if self.rms_consistent is None else 100.0 * self.rms_consistent / self.rms_torque

    @property
    def relative_least_squares(self) -> np.ndarray:
        """(n,) RMS error / RMS torque [%] of the least-squares fit with effects."""
        return 100.0 * self.rms_least_squares / self.rms_torque

    def effect_values(self, consistent: bool = False) -> list[tuple[Term, str, float, float]]:
        """(term, coefficient, value, std) for every chosen effect coefficient, in order: of the
        least-squares fit, or with ``consistent`` of the physically consistent one (std NaN)."""
        b = len(self.base_names)
        values = self.consistent.effects if consistent else self.selection.fit.x[b:]
        stds = np.full(values.size, np.nan) if consistent else self.selection.fit.std[b:]
        names = [(term, name) for term in self.selection.terms for name in coefficient_names(term, self.offset_runs)]
        return [(term, name, float(v), float(s)) for (term, name), v, s in zip(names, values, stds)]
