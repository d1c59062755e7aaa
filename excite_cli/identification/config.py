"""The identification configs, validated once at load (pydantic): ``excite identify`` (robot, data,
preprocessing, identification) and the effects file of ``excite simulate``. Every field is documented
in README.md ("Identification config", "Effects file") with its unit and default."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal, Optional, Union

import numpy as np
from pydantic import Field, NonNegativeFloat, PositiveFloat, field_validator, model_validator

from excite_cli.config import MAX_SEED, Problem, RobotConfig, Section
from excite_cli.identification.effects import EFFECT_NAMES, EFFECTS, SHAPE_GRID

Effect = Literal[EFFECT_NAMES]
#: The default candidates: every effect but the position-dependent ones, which, even guarded to the fit
#: data's q range, fitted the seen phases of the real Panda run and cost on unseen ones (README), so
#: they are opt-in.
DEFAULT_CANDIDATES = tuple(e for e in EFFECT_NAMES if not EFFECTS[e].position)
#: Default regularization weights λ of the consistent fit, among which the cross-validation chooses.
REGULARIZATION = (1e-5, 1e-4, 1e-3, 1e-2, 1e-1)
#: Default ratios r of the couplings q_i + r q_(i+1) the search proposes between neighbouring joints
#: when no transmission is declared (a motor turning with two joints: a coupled wrist).
COUPLING_RATIOS = (1.0, -1.0)


Column = Union[Annotated[int, Field(ge=0, strict=True)], str]  # strict: `time: true` is not column 1
#: Highest sample rate [Hz] (of the decimated data, of a simulated run).
MAX_RATE = 100_000.0


class ColumnsConfig(Section):
    """Columns of measured data, in active-joint order, by name or by 0-based position, and the factor
    of any column recorded in other units (SI value = recorded value × factor: encoder counts → rad,
    mA → A, ms → s) (README: identification config)."""

    time: Optional[Column] = "time"
    q: list[Column] = Field(min_length=1)
    qd: Optional[list[Column]] = None
    qdd: Optional[list[Column]] = None
    tau: Optional[list[Column]] = None
    current: Optional[list[Column]] = None
    factors: dict[str, float] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _torque_source(self) -> "ColumnsConfig":
        if (self.tau is None) == (self.current is None):
            raise ValueError("give exactly one of tau or current columns")
        named = {str(k) for keys in (self.q, self.qd, self.qdd, self.tau, self.current) for k in keys or []}
        named.add(str(self.time))
        for key, factor in self.factors.items():
            if key not in named:
                raise ValueError(f"factors names '{key}', which is not one of the columns given")
            if factor == 0.0 or not np.isfinite(factor):
                raise ValueError(
                    f"the factor of '{key}' must be a finite number other than 0 (SI value per recorded unit)"
                )
        return self


class PayloadConfig(Section):
    """A known payload of a run: mass [kg], centre of mass [m] and inertia about it [kg·m²]
    (Ixx, Ixy, Iyy, Ixz, Iyz, Izz) in ``frame`` (default: the link of the last active joint)."""

    mass: float = Field(gt=0.0)
    com: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: tuple[float, float, float, float, float, float] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    frame: Optional[str] = None

    @field_validator("inertia")
    @classmethod
    def _a_body_can_have_it(cls, inertia):
        xx, xy, yy, xz, yz, zz = inertia
        moments = np.linalg.eigvalsh(np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]))
        tolerance = 1e-9 * max(1.0, moments.max())
        if moments.min() < -tolerance or 2 * moments.max() > moments.sum() + tolerance:
            raise ValueError(
                f"no body has principal moments {', '.join(f'{m:.4g}' for m in moments)} kg·m²; expected them ≥ 0 "
                "and each at most the sum of the other two (Ixx, Ixy, Iyy, Ixz, Iyz, Izz about the centre of mass)"
            )
        return inertia


class RunConfig(Section):
    """One measured run: file, optional crop [s], role (fit, validation or time blocks), a known payload."""

    file: Union[str, list[str]]
    crop: Optional[tuple[float, float]] = None
    role: Literal["fit", "validation", "blocks"] = "blocks"
    payload: Optional[PayloadConfig] = None

    @property
    def files(self) -> list[str]:
        """The run's file or files, as written."""
        return [self.file] if isinstance(self.file, str) else list(self.file)

    @property
    def label(self) -> str:
        """The file name with the crop, for tables and reports, e.g. ``run.csv [7.8, 13.2] s``."""
        return " + ".join(Path(f).name for f in self.files) + (
            f" [{self.crop[0]:g}, {self.crop[1]:g}] s" if self.crop else ""
        )


class TransmissionConfig(Section):
    """The transmissions from the datasheet: gear ratios N (n,) and a coupling matrix C (n, n) (default
    the identity), so that motor angles are m = R q with R = diag(N) C and joint torques τ = Rᵀ τ_m. A
    coupled wrist whose motor 6 turns with q5 + q6 has C row 6 = [0, 0, 0, 0, 1, 1]."""

    gear_ratios: list[float] = Field(min_length=1)
    coupling: Optional[list[list[float]]] = None

    @field_validator("gear_ratios")
    @classmethod
    def _nonzero_ratios(cls, values):
        if any(v == 0.0 or not np.isfinite(v) for v in values):
            raise ValueError("every gear ratio must be a finite number other than 0")
        return values

    @model_validator(mode="after")
    def _invertible(self) -> "TransmissionConfig":
        n = len(self.gear_ratios)
        if self.coupling is not None:
            C = np.asarray(self.coupling, dtype=float)
            if C.shape != (n, n) or not np.all(np.isfinite(C)):
                raise ValueError(f"coupling must be {n} rows of {n} numbers, one per motor and joint")
            if abs(np.linalg.det(C)) < 1e-9:
                raise ValueError("coupling must be invertible: every joint angle follows from the motor angles")
        return self

    def reduction(self) -> np.ndarray:
        """R (n, n) = diag(N) C: motor angles m = R q."""
        n = len(self.gear_ratios)
        C = np.eye(n) if self.coupling is None else np.asarray(self.coupling, dtype=float)
        return np.asarray(self.gear_ratios, dtype=float)[:, None] * C


class DataConfig(Section):
    """Measured runs, their columns (for ROS bags: the JointState ``topic``, joints by name), angle
    unit, torque constants [Nm/A], signs, validation blocks, what to do with rows that cannot be used
    (stop with an error, or drop and count them)."""

    runs: list[RunConfig] = Field(min_length=1)
    columns: Optional[ColumnsConfig] = None
    topic: str = "/joint_states"
    angle_unit: Literal["rad", "deg"] = "rad"
    torque_constants: Optional[list[float]] = None
    signs: Optional[list[float]] = None
    validation_blocks: int = Field(4, ge=2, le=100)
    bad_rows: Literal["error", "drop"] = "error"
    transmission: Optional[TransmissionConfig] = None
    motor_side: bool = False
    sample_rate: Optional[PositiveFloat] = None

    @model_validator(mode="after")
    def _consistent(self) -> "DataConfig":
        if self.motor_side and self.transmission is None:
            raise ValueError("motor_side needs data.transmission (gear ratios and coupling) to reach the joints")
        if self.columns is not None and self.columns.time is None and self.sample_rate is None:
            raise ValueError("files without a time column (columns.time: null) need data.sample_rate [Hz]")
        return self

    @field_validator("torque_constants")
    @classmethod
    def _nonzero(cls, values):
        if values is not None and any(v <= 0.0 for v in values):
            raise ValueError(
                "every torque constant must be > 0 Nm/A (the motor's, from its datasheet); "
                "a motor mounted the other way round is data.signs: -1"
            )
        return values

    @field_validator("signs")
    @classmethod
    def _plus_or_minus_one(cls, values):
        if values is not None and any(v not in (1.0, -1.0) for v in values):
            raise ValueError("every sign must be 1 or -1")
        return values


class PreprocessingConfig(Section):
    """Decimated rate [Hz] (default: min(200 Hz, the data's rate)), low-pass cut-off [Hz] (default from
    the bandwidth), filter order."""

    sample_rate: Optional[float] = Field(None, gt=0.0, le=MAX_RATE)
    cutoff: Optional[float] = Field(None, gt=0.0)
    filter_order: int = Field(4, ge=1, le=10)


class IdentificationConfig(Section):
    """LS or WLS, declared and candidate effects (position effects guarded to the fit data's q range
    unless ``position_guard`` is off), the selection's cross-validation folds (what each holds
    out, how many time blocks) and threshold,
    friction shape velocities [rad/s] (a Stribeck or held velocity: one value, or a grid the
    selection searches), the fit (least squares, physically consistent, or the one the cross-validation
    prefers together with the model) and the consistent fit's regularization weights toward the URDF."""

    method: Literal["wls", "ls"] = "wls"
    declared_effects: dict[str, list[Effect]] = Field(default_factory=dict)
    candidates: list[Effect] = Field(default_factory=lambda: list(DEFAULT_CANDIDATES))
    position_guard: bool = True
    folds_by: Literal["auto", "recording", "run", "time_block"] = "auto"
    folds: int = Field(6, ge=3, le=50)
    min_improvement: float = Field(0.02, ge=0.0, lt=1.0)
    coulomb_velocity: PositiveFloat = 0.01
    stribeck_velocity: list[PositiveFloat] = Field(default_factory=lambda: list(SHAPE_GRID), min_length=1)
    held_velocity: list[PositiveFloat] = Field(default_factory=lambda: list(SHAPE_GRID), min_length=1)
    max_effects: int = Field(60, ge=0)
    fit: Literal["auto", "least_squares", "consistent"] = "auto"
    regularization: list[NonNegativeFloat] = Field(default_factory=lambda: list(REGULARIZATION), min_length=1)
    coupling_ratios: list[float] = Field(default_factory=lambda: list(COUPLING_RATIOS))
    coupling_improvement: float = Field(0.2, ge=0.0, lt=10.0)

    @field_validator("stribeck_velocity", "held_velocity", "regularization", mode="before")
    @classmethod
    def _one_or_grid(cls, value):
        return [value] if isinstance(value, (int, float)) else value


class IdentifyProblem(Section):
    """``excite identify`` config: the robot as for ``optimize``, then data, preprocessing, identification."""

    robot: RobotConfig
    data: DataConfig
    preprocessing: PreprocessingConfig = PreprocessingConfig()
    identification: IdentificationConfig = IdentificationConfig()
    output: str = "results/identification.h5"

    source_path: Optional[Path] = Field(None, exclude=True)
    source_text: str = Field("", exclude=True)

    folder = Problem.folder


class SimulationConfig(Section):
    """``excite simulate`` effects file: what the simulated robot has beyond its URDF rigid body."""

    sample_rate: float = Field(1000.0, gt=0.0, le=MAX_RATE)
    periods: int = Field(2, ge=1, le=1000)
    timestamp_jitter: float = Field(0.0, ge=0.0, lt=0.5)
    torque_noise: float = Field(0.0, ge=0.0)
    position_noise: float = Field(0.0, ge=0.0)
    seed: int = Field(0, ge=0, le=MAX_SEED)
    effects: dict[Effect, dict[str, Union[float, tuple[float, float]]]] = Field(default_factory=dict)
    stribeck_velocity: float = Field(0.1, gt=0.0)
    coulomb_velocity: float = Field(0.01, gt=0.0)
    held_velocity: float = Field(0.02, gt=0.0)
    transmission: Optional[TransmissionConfig] = None
    motor_effects: dict[Literal["armature", "coulomb", "viscous"], dict[str, float]] = Field(default_factory=dict)
    motor_side: bool = False

    @model_validator(mode="after")
    def _motors_need_the_transmission(self) -> "SimulationConfig":
        if (self.motor_effects or self.motor_side) and self.transmission is None:
            raise ValueError("motor_effects and motor_side need a transmission (gear ratios and coupling)")
        return self
