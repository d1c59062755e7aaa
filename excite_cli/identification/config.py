"""The ``excite identify`` config (robot, data, preprocessing, identification), validated once at load
(pydantic); each field's docstring is its description with its unit (``excite schema``, the config
reference). The effects file of ``excite simulate``: :mod:`~excite_cli.identification.simulation_config`."""

from __future__ import annotations

from typing import Literal, Optional

from pydantic import Field, NonNegativeFloat, PositiveFloat, field_validator

from excite_cli.config import COULOMB_VELOCITY, ConfigFile, RobotConfig, Section
from excite_cli.effects import EFFECT_NAMES, SHAPE_GRID
from excite_cli.identification.data_config import MAX_RATE, DataConfig

Effect = Literal[EFFECT_NAMES]
#: The default candidates: every effect. The position-dependent ones pay a higher price
#: (``position_improvement``): at the price of the others they fitted the seen phases of the real Panda
#: run and cost on unseen ones (docs/figures.md).
DEFAULT_CANDIDATES = EFFECT_NAMES
#: Default regularization weights λ of the consistent fit, among which the cross-validation chooses.
REGULARIZATION = (1e-5, 1e-4, 1e-3, 1e-2, 1e-1)
#: Default ratios r of the couplings q_i + r q_(i+1) the search proposes between neighbouring joints
#: when no transmission is declared (a motor turning with two joints: a coupled wrist).
COUPLING_RATIOS = (1.0, -1.0)


class PreprocessingConfig(Section):
    """Decimated rate [Hz] (default: min(200 Hz, the data's rate)), low-pass cut-off [Hz] (default from
    the bandwidth), filter order."""

    sample_rate: Optional[float] = Field(None, gt=0.0, le=MAX_RATE)
    """Rate after decimation [Hz] (default min(200 Hz, the data's))."""
    cutoff: Optional[float] = Field(None, gt=0.0)
    """Low-pass cut-off [Hz] (default 10 × the 99 % power bandwidth of q, at least 5 Hz)."""
    filter_order: int = Field(4, ge=1, le=10)
    """Butterworth filter order."""


class IdentificationConfig(Section):
    """LS or WLS, declared and candidate effects (position effects guarded to the fit data's q range
    unless ``position_guard`` is off), the selection's cross-validation folds (what each holds
    out, how many time blocks) and threshold,
    friction shape velocities [rad/s] (a Stribeck or held velocity: one value, or a grid the
    selection searches), the fit (least squares, physically consistent, or the one the cross-validation
    prefers together with the model) and the consistent fit's regularization weights toward the URDF."""

    method: Literal["wls", "ls"] = "wls"
    """`wls` (weighted least squares) or `ls`."""
    declared_effects: dict[str, list[Effect]] = Field(default_factory=dict)
    """{joint or '*': [effects]} in the model from the start, never removed."""
    candidates: list[Effect] = Field(default_factory=lambda: list(DEFAULT_CANDIDATES))
    """Effects the search may add (default all; `motor`: a coupled motor's inertia and friction together)."""
    position_guard: bool = True
    """Hold position-dependent effects at their value outside the fit data's q range."""
    folds_by: Literal["auto", "recording", "run", "time_block"] = "auto"
    """What a cross-validation fold holds out: `auto`, `recording`, `run` or `time_block`."""
    folds: int = Field(6, ge=3, le=50)
    """K, time-block folds of the cross-validation."""
    min_improvement: float = Field(0.02, ge=0.0, lt=1.0)
    """Cut [1] of the CV error every effect must buy on time-block folds (distinct recordings: paired test)."""
    coulomb_velocity: PositiveFloat = COULOMB_VELOCITY
    """v_c of the smooth sign tanh(q̇/v_c) [rad/s]."""
    stribeck_velocity: list[PositiveFloat] = Field(default_factory=lambda: list(SHAPE_GRID), min_length=1)
    """The grid [rad/s] the search picks Stribeck's v_s from (one value fixes it)."""
    held_velocity: list[PositiveFloat] = Field(default_factory=lambda: list(SHAPE_GRID), min_length=1)
    """The grid [rad/s] the search picks held friction's v_h from (one value fixes it)."""
    max_effects: int = Field(60, ge=0)
    """Cap on added effects."""
    fit: Literal["auto", "least_squares", "consistent"] = "auto"
    """The reported fit: `auto` (chosen by cross-validation), `least_squares` or `consistent`."""
    least_squares_margin: float = Field(0.5, ge=0.0, lt=10.0)
    """m [1]: `fit: auto` on time blocks takes least squares only where the consistent CV error is ≥ (1 + m) × its."""
    regularization: list[NonNegativeFloat] = Field(default_factory=lambda: list(REGULARIZATION), min_length=1)
    """λ [1] of the consistent fit (weight of the distance to the URDF's parameters); a list to pick from."""
    coupling_ratios: list[float] = Field(default_factory=lambda: list(COUPLING_RATIOS))
    """Ratios r [1] of the coupled-motor candidates q_i + r q_(i+1) without a transmission."""
    coupling_improvement: float = Field(0.2, ge=0.0, lt=10.0)
    """Cut [1] of the cross-validated error a coupled motor effect must buy (time-block folds only)."""
    position_improvement: float = Field(0.25, ge=0.0, lt=10.0)
    """Cut [1] of the cross-validated error a position-dependent effect must buy (time-block folds only)."""

    @field_validator("stribeck_velocity", "held_velocity", "regularization", mode="before")
    @classmethod
    def _one_or_grid(cls, value):
        return [value] if isinstance(value, (int, float)) else value


class IdentifyProblem(ConfigFile):
    """``excite identify`` config: the robot as for ``optimize``, then data, preprocessing, identification."""

    robot: RobotConfig
    """The robot, as in an optimize config."""
    data: DataConfig
    """The measured runs and how to read them."""
    preprocessing: PreprocessingConfig = PreprocessingConfig()
    """Resampling, low-pass filter and decimation."""
    identification: IdentificationConfig = IdentificationConfig()
    """The fit and the search for effects the model lacks."""
    output: str = "results/identification.h5"
    """Path of the HDF5 report (relative to the working directory)."""
