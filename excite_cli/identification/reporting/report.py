"""The identify report: what ``excite identify`` found, as one typed record that the report file,
the printed tables, the figures and ``--urdf-out`` read."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from excite_cli.identification.choice.fit_records import FitChoice
from excite_cli.identification.choice.selection import Selection
from excite_cli.identification.effects import Term, coefficient_names
from excite_cli.identification.fitting.dataset import Dataset
from excite_cli.identification.fitting.least_squares import torque_errors
from excite_cli.identification.fitting.noise_level import NoiseLevel
from excite_cli.identification.fitting.physical import ConsistentFit

#: [% points] of mean relative validation error by which the fit not chosen must beat the chosen one
#: for a warning.
DISAGREEMENT = 1.0


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
        rate: the decimated sample rate of the fit and validation data [Hz] (rows per second of the
            base regressor, per joint).
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
        noise_levels: (n,) each joint's noise fitted to the residual on the fit data, σ² = a² + (ρτ)²
            (:mod:`~excite_cli.identification.fitting.noise_level`), None for a dead channel; an empty
            list when the fit data are too short for it.
        noise_gain: the median over the fit instants of the share of white noise's variance
            their low-pass leaves (:func:`~excite_cli.identification.fitting.noise_level.noise_gain`).
        dead: (n,) the joints whose torque channel carries no signal
            (:mod:`~excite_cli.identification.fitting.channels`): their relative errors are of the
            model's predicted RMS torque instead of the measured one, and no mean includes them.
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
    rate: float
    dropped: list[tuple[str, int]] = field(default_factory=list)
    run_names: list[str] = field(default_factory=list)
    offset_runs: list[str] = field(default_factory=list)
    ladder: list[tuple[str, float, float]] = field(default_factory=list)
    q_range: np.ndarray | None = None
    warnings: list[str] = field(default_factory=list)
    dead: np.ndarray | None = None
    noise_levels: list[NoiseLevel | None] = field(default_factory=list)
    noise_gain: float = 1.0

    @property
    def live(self) -> np.ndarray:
        """(n,) the joints whose torque channel carries signal (every joint when all are dead)."""
        live = np.ones(len(self.joints), dtype=bool) if self.dead is None else ~np.asarray(self.dead, dtype=bool)
        return live if live.any() else np.ones_like(live)

    def mean(self, relative: np.ndarray) -> float:
        """The mean over the live joints of per-joint relative errors (n,) [%]."""
        return float(np.asarray(relative)[self.live].mean())

    @property
    def reference(self) -> np.ndarray:
        """(n,) the RMS torque [Nm] each relative error is of: the measured one, or for a dead channel
        (or one without torque) the model's predicted RMS torque (1 Nm where that is zero too)."""
        predicted = np.sqrt(np.mean(self.predicted_after**2, axis=0))
        measured = np.where(self.live & (self.rms_torque > 0), self.rms_torque, predicted)
        return np.where(measured > 0, measured, 1.0)

    @property
    def worse_than_rigid_body(self) -> np.ndarray:
        """(n,) the joints with signal whose validation error ends above the rigid body's."""
        return (self.rms_after > self.rms_before) & self.live

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
        return 100.0 * self.rms_before / self.reference

    @property
    def relative_after(self) -> np.ndarray:
        """(n,) RMS error / RMS torque [%] after."""
        return 100.0 * self.rms_after / self.reference

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
        return None if self.rms_consistent is None else 100.0 * self.rms_consistent / self.reference

    @property
    def relative_least_squares(self) -> np.ndarray:
        """(n,) RMS error / RMS torque [%] of the least-squares fit with effects."""
        return 100.0 * self.rms_least_squares / self.reference

    def fit_disagreement(self) -> list[str]:
        """A warning when the fit not chosen predicts the validation data better than the chosen one by
        more than ``DISAGREEMENT`` points of mean relative error (the folds did not foresee the
        validation motion), else nothing."""
        if self.relative_consistent is None:
            return []
        chosen, name = self.mean(self.relative_after), self.fit_choice.name
        other_name, other = (
            ("least squares", self.relative_least_squares)
            if self.fit_choice.is_consistent
            else ("the consistent fit", self.relative_consistent)
        )
        if self.mean(other) >= chosen - DISAGREEMENT:
            return []
        return [
            f"the chosen fit ({name}) predicts the validation data at {chosen:.1f} %, {other_name} at "
            f"{self.mean(other):.1f} %: the fit data's folds did not foresee the validation motion (more or "
            "longer fit runs, or identification.fit to choose)"
        ]

    def effect_values(self, consistent: bool = False) -> list[tuple[Term, str, float, float]]:
        """(term, coefficient, value, std) for every chosen effect coefficient, in order: of the
        least-squares fit (std NaN for a coefficient held at its bound 0:
        :attr:`~excite_cli.identification.fitting.least_squares.Fit.held`), or with
        ``consistent`` of the physically consistent one (std NaN), followed
        by its rotors held apart from the bodies, as the armature of their joints (what a model file
        of its bodies lacks)."""
        b = len(self.base_names)
        fit = self.selection.fit
        values = self.consistent.effects if consistent else fit.x[b:]
        stds = np.full(values.size, np.nan) if consistent else fit.std[b:].copy()
        if not consistent and fit.held.size:
            stds[fit.held[b:]] = np.nan  # held at its bound 0: no two-sided std
        names = [(term, name) for term in self.selection.terms for name in coefficient_names(term, self.offset_runs)]
        out = [(term, name, float(v), float(s)) for (term, name), v, s in zip(names, values, stds)]
        if consistent:
            rotors = zip(self.consistent.rotor_joints, self.consistent.rotors)
            out += [(Term("armature", self.joints.index(j)), "Ia", float(a), float("nan")) for j, a in rotors]
        return out
