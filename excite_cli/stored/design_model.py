"""An identify report as the next design's model and prior data. Its chosen effects are the model
the next trajectory is designed for (``effects.model`` of an ``optimize`` config): each joint's Coulomb
and viscous friction, armature and torque offset, and each coupled motor with its transmission row
(``/identification/effect_coupling``). Effects the design cannot hold as columns (asymmetric,
Stribeck, held and load-dependent friction: nonlinear in a shape or a first fit; springs and position
harmonics) are named and left out. As ``sequence.prior`` its rows are weighed as identification
weighs them (:class:`MeasuredPrior`), and hold the columns of those effects too
(:func:`~excite_cli.identification.reporting.prior_rows.prior_rows` wrote them), so one report is both
the model and the prior data of the next design."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from excite_cli.config import EffectsConfig, MotorConfig
from excite_cli.effects import DESIGNED, EFFECTS
from excite_cli.errors import ExciteError, ExciteWarning
from excite_cli.stored.report import StoredReport


@dataclass(frozen=True)
class ReportModel:
    """The designable part of an identify report's model.

    Attributes:
        joints: {joint: [effects among ``DESIGNED``]}.
        motors: coupled motors: (joints, transmission row) each.
        coulomb_velocity: v_c [rad/s] of the report's smooth sign.
        left_out: the report's other effects, as ``effect (joint)``.
    """

    joints: dict[str, list[str]]
    motors: list[tuple[list[str], list[float]]]
    coulomb_velocity: float
    left_out: list[str]


def report_model(report: StoredReport) -> ReportModel:
    """The designable part of the model of ``report``: each joint's effects among ``DESIGNED``, each
    coupled motor (a motor on one joint's own row: that joint, ratio 1), the others named; the
    consistent fit's rotors that the effect search did not choose are bodies, not effects to design for."""
    joints: dict[str, list[str]] = {}
    motors: list[tuple[list[str], list[float]]] = []
    left_out: list[str] = []
    for effect, joint, _, coupling in report.terms[: len(report.terms) - report.rotors]:
        if EFFECTS[effect].parts:  # a motor: its rotor inertia and friction in its coordinate
            moved = [] if coupling is None else np.flatnonzero(coupling)
            motor = (
                ([report.joints[k] for k in moved], [float(coupling[k]) for k in moved])
                if coupling
                else ([joint], [1.0])
            )
            motors += [] if motor in motors else [motor]
        elif effect in DESIGNED:
            kinds = joints.setdefault(joint, [])
            kinds += [] if effect in kinds else [effect]
        elif f"{effect} ({joint})" not in left_out:
            left_out.append(f"{effect} ({joint})")
    return ReportModel(joints, motors, report.coulomb_velocity, left_out)


def with_report_model(cfg: EffectsConfig, report: StoredReport, path: Path, joint_names: list[str]) -> EffectsConfig:
    """``cfg`` with the effects of the identify ``report`` (read from ``path``) added (the report's
    smooth-sign velocity taken); an :class:`~excite_cli.errors.ExciteWarning` names the effects left out.

    Raises:
        ExciteError: (``effects.model``) a report whose joints are not all active in this problem (a
            report of another robot or joint set).
    """
    model = report_model(report)
    unknown = [j for j in [*model.joints, *(j for joints, _ in model.motors for j in joints)] if j not in joint_names]
    if unknown:
        raise ExciteError(
            "effects.model", f"{path} identified joint '{unknown[0]}', which is not an active joint of this problem"
        )
    if model.left_out:
        warnings.warn(
            f"effects.model: {', '.join(model.left_out)} from {path.name} are not designed for (nonlinear in a "
            "shape, or position-dependent)",
            ExciteWarning,
        )
    joints = {name: list(kinds) for name, kinds in cfg.joints.items()}
    for name, kinds in model.joints.items():
        joints[name] = joints.get(name, []) + [k for k in kinds if k not in joints.get(name, [])]
    motors = list(cfg.motors) + [MotorConfig(joints=j, transmission=t) for j, t in model.motors]
    return cfg.model_copy(update={"joints": joints, "motors": motors, "coulomb_velocity": model.coulomb_velocity})


#: The largest joint error a report may give as prior data [Nm] (the noise a design may be for).
LARGEST_ERROR = 1e6
#: The highest sample rate a report's rows may have [Hz].
HIGHEST_RATE = 1e6
#: The smallest absolute noise a measured noise level gives a joint's rows, as a share of its σ_j: a fitted
#: a of 0 (noise all relative) would weigh a row of zero torque without bound.
MEASURED_FLOOR = 0.01


@dataclass(frozen=True)
class MeasuredPrior:
    """How an identify report's rows weigh as prior data C₀ (Eq. 41) of the next design, as weighted
    least squares weighs them: each row divided by its noise (the measured level at the row's predicted
    torque, or its joint's σ_j), and one second of recording worth one second of a trajectory on the
    cost grid.

    Attributes:
        joints: (n,) the report's joints, in its rows' order.
        sigma: (n,) σ_j [Nm]: each joint's RMS torque error of the reported model on the validation
            data (``rms_after``), what the fit leaves unexplained, noise included.
        rate: the report's decimated sample rate [Hz]: regressor rows per second and joint.
        level: (n, 3) each joint's fitted noise of its rows, a [Nm] and ρ [1] of σ² = a² + (ρτ)² and a's
            95 % upper bound [Nm] (:mod:`~excite_cli.identification.fitting.noise_level`), NaN for a
            dead channel; None: the report has none (its σ_j alone weigh the rows).
    """

    joints: list[str]
    sigma: np.ndarray
    rate: float
    level: np.ndarray | None = None

    @property
    def floored(self) -> np.ndarray:
        """(n,) σ_j [Nm], floored at 1e-9 of the largest (a joint the model explains exactly)."""
        return np.maximum(self.sigma, 1e-9 * self.sigma.max())

    @property
    def noise(self) -> float:
        """σ̄ [Nm], the geometric mean of σ_j: the noise of one weighted row."""
        return float(np.exp(np.log(self.floored).mean()))

    def weights(self) -> np.ndarray:
        """(n,) σ̄ / σ_j (1 for equal noise on every joint): weighted least squares' weights (Gautier
        1997), relative so the criterion keeps its scale."""
        return self.noise / self.floored

    def noise_parts(self) -> tuple[np.ndarray, np.ndarray]:
        """(n,) a_j [Nm] and (n,) ρ_j [1] of each joint's rows' noise σ² = a² + (ρτ)²: the fitted
        ``level`` with a's upper bound for a (the largest absolute part the recording cannot rule out: a
        fitted a is poorly determined, often 0, where the growing part dominates, and would trust the
        joint's small-torque rows more than the data support; bench/noise_loop.py), floored at
        :data:`MEASURED_FLOOR` σ_j; σ_j and ρ = 0 on a dead channel or without a fitted level."""
        if self.level is None:
            return self.floored, np.zeros(len(self.joints))
        fitted = np.isfinite(self.level).all(axis=1)  # a dead channel keeps its σ_j
        level = np.nan_to_num(self.level)
        a = np.maximum(level[:, 2], MEASURED_FLOOR * self.floored)
        return np.where(fitted, a, self.floored), np.where(fitted, level[:, 1], 0.0)

    def row_weights(self, predicted: np.ndarray) -> np.ndarray:
        """σ̄ / √(a_j² + ρ_j² τ̂²) (M,) of the report's M rows (instants one after another, n joints
        each) whose predicted torques are ``predicted`` (M,) [Nm] (the reported model's), a and ρ of
        :meth:`noise_parts` (without a fitted level σ̄/σ_j, :meth:`weights`): weighted least squares'
        weights of a noise growing with the torque (Gautier 1997 with a noise that depends on the sample).

        Raises:
            ValueError: M is not a whole number of instants of the n joints.
        """
        if predicted.size % len(self.joints):
            raise ValueError(f"{predicted.size} rows are not instants of {len(self.joints)} joints")
        a, rho = (np.tile(x, predicted.size // len(self.joints)) for x in self.noise_parts())
        return self.noise / np.sqrt(a**2 + (rho * predicted) ** 2)

    def time_scale(self, cost_period: float) -> float:
        """√(1 / (cost_period · rate)): the information of a recording is a Riemann sum of ∫ YᵀWᵀWY dt
        at its rate and the design's at 1/cost_period rows per second, so each recorded row is scaled
        so that both sums approximate the same integral per second (Swevers et al. 1997 take the
        information matrix as that integral over the experiment)."""
        return float(np.sqrt(1.0 / (cost_period * self.rate)))


def measured_prior_of(report: StoredReport, path: Path) -> MeasuredPrior:
    """How the rows of ``report`` (read from ``path``, ``sequence.prior``) weigh as prior data: its
    joints' validation errors (``/identification/rms_after``) and its rows' rate (``/regressor``
    attribute ``sample_rate_Hz``).

    Raises:
        ExciteError: (``sequence.prior``) a report of an earlier version without what weighs its rows, or
            whose errors, noise levels or sample rate no weighing can use (not finite, negative, all zero,
            not one per joint; a rate that is not positive).
    """
    sigma, rate, joints = report.rms_after, report.rate, report.joints
    if sigma is None or rate is None:
        raise ExciteError(
            "sequence.prior",
            f"{path} is an identify report of an earlier excite: without /identification/rms_after and the "
            "regressor's sample_rate_Hz its rows cannot be weighed as its measurements were",
            path,
            "a report of this version (identify its runs again)",
        )
    if sigma.shape != (len(joints),) or not np.all(np.isfinite(sigma)) or np.any(sigma < 0) or not np.any(sigma > 0):
        raise ExciteError(
            "sequence.prior",
            f"{path}: /identification/rms_after must hold each of its {len(joints)} joints' error, finite, not "
            "negative and not all zero (damaged?)",
        )
    if sigma.max() > LARGEST_ERROR:
        j = int(np.argmax(sigma))
        raise ExciteError(
            "sequence.prior",
            f"{path}: /identification/rms_after gives joint '{joints[j]}' an error of {sigma[j]:g} Nm (damaged?)",
            sigma[j],
            f"at most {LARGEST_ERROR:g} Nm",
        )
    if not (np.isfinite(rate) and 0 < rate <= HIGHEST_RATE):
        raise ExciteError(
            "sequence.prior",
            f"{path}: its sample rate sample_rate_Hz is {rate:g}",
            rate,
            f"a positive rate up to {HIGHEST_RATE:g} Hz",
        )
    level = report.noise_level
    largest = [LARGEST_ERROR, 10.0, LARGEST_ERROR]  # a, ρ, a's upper bound
    if level is not None and not (np.all(np.isnan(level) | ((level >= 0) & (level <= largest)))):
        raise ExciteError(
            "sequence.prior",
            f"{path}: /identification/noise_level must give each joint a and its bound in 0 to {LARGEST_ERROR:g} "
            "Nm and ρ in 0 to 10 (NaN for a dead channel) (damaged?)",
        )
    return MeasuredPrior(joints, sigma, rate, level if level is not None and np.isfinite(level).any() else None)
