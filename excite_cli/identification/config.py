"""The identification configs, validated once at load (pydantic): ``excite identify`` (robot, data,
preprocessing, identification) and the effects file of ``excite simulate``. Every field is documented
in README.md ("Identification config", "Effects file") with its unit and default."""

from __future__ import annotations

from pathlib import Path
from typing import Literal, Optional, Union

from pydantic import Field, NonNegativeInt, model_validator

from excite_cli.config import Problem, RobotConfig, Section


EFFECT_NAMES = ("coulomb", "coulomb_asymmetric", "viscous", "stribeck", "offset", "armature", "spring", "gravity_compensator",
                "position_2", "viscous_asymmetric", "held", "load_coulomb")
#: The default candidates: adding the last four to them made the greedy selection worse on the real
#: Panda run (README), so they are opt-in through ``identification.candidates``.
DEFAULT_CANDIDATES = EFFECT_NAMES[:8]
Effect = Literal["coulomb", "coulomb_asymmetric", "viscous", "stribeck", "offset", "armature", "spring", "gravity_compensator",
                 "position_2", "viscous_asymmetric", "held", "load_coulomb"]


Column = Union[NonNegativeInt, str]


class ColumnsConfig(Section):
    """Columns of measured data, in active-joint order, by name or by 0-based position (README:
    identification config)."""

    time: Column = "time"
    q: list[Column] = Field(min_length=1)
    qd: Optional[list[Column]] = None
    qdd: Optional[list[Column]] = None
    tau: Optional[list[Column]] = None
    current: Optional[list[Column]] = None

    @model_validator(mode="after")
    def _torque_source(self) -> "ColumnsConfig":
        if (self.tau is None) == (self.current is None):
            raise ValueError("give exactly one of tau or current columns")
        return self


class RunConfig(Section):
    """One measured run: file, optional crop [s], role (fit, validation or time blocks)."""

    file: str
    crop: Optional[tuple[float, float]] = None
    role: Literal["fit", "validation", "blocks"] = "blocks"

    @property
    def label(self) -> str:
        """The file name with the crop, for tables and reports, e.g. ``run.csv [7.8, 13.2] s``."""
        return Path(self.file).name + (f" [{self.crop[0]:g}, {self.crop[1]:g}] s" if self.crop else "")


class DataConfig(Section):
    """Measured runs, their columns, angle unit, torque constants [Nm/A], signs, validation blocks,
    what to do with rows that cannot be used (stop with an error, or drop and count them)."""

    runs: list[RunConfig] = Field(min_length=1)
    columns: ColumnsConfig
    angle_unit: Literal["rad", "deg"] = "rad"
    torque_constants: Optional[list[float]] = None
    signs: Optional[list[float]] = None
    validation_blocks: int = Field(4, ge=2)
    bad_rows: Literal["error", "drop"] = "error"


class PreprocessingConfig(Section):
    """Decimated rate [Hz], low-pass cut-off [Hz] (default from the bandwidth), filter order."""

    sample_rate: float = Field(200.0, gt=0.0)
    cutoff: Optional[float] = Field(None, gt=0.0)
    filter_order: int = Field(4, ge=1, le=10)


class IdentificationConfig(Section):
    """LS or WLS, declared and candidate effects, selection thresholds, friction shape constants [rad/s],
    physically consistent standard parameters and their regularization toward the URDF."""

    method: Literal["wls", "ls"] = "wls"
    declared_effects: dict[str, list[Effect]] = Field(default_factory=dict)
    candidates: list[Effect] = Field(default_factory=lambda: list(DEFAULT_CANDIDATES))
    significance: float = Field(1e-3, gt=0.0, lt=1.0)
    min_improvement: float = Field(0.01, ge=0.0, lt=1.0)
    stribeck_velocity: float = Field(0.1, gt=0.0)
    coulomb_velocity: float = Field(0.01, gt=0.0)
    held_velocity: float = Field(0.02, gt=0.0)
    max_effects: int = Field(60, ge=0)
    physical_consistency: bool = False
    regularization: float = Field(1e-3, ge=0.0)


class IdentifyProblem(Section):
    """``excite identify`` config: the robot as for ``optimize``, then data, preprocessing, identification."""

    robot: RobotConfig
    data: DataConfig
    preprocessing: PreprocessingConfig = PreprocessingConfig()
    identification: IdentificationConfig = IdentificationConfig()
    output: str = "results/identification.h5"

    source_path: Optional[Path] = Field(None, exclude=True)
    source_text: str = Field("", exclude=True)

    resolve = Problem.resolve


class SimulationConfig(Section):
    """``excite simulate`` effects file: what the simulated robot has beyond its URDF rigid body."""

    sample_rate: float = Field(1000.0, gt=0.0)
    periods: int = Field(2, ge=1)
    timestamp_jitter: float = Field(0.0, ge=0.0, lt=0.5)
    torque_noise: float = Field(0.0, ge=0.0)
    position_noise: float = Field(0.0, ge=0.0)
    seed: int = Field(0, ge=0)
    effects: dict[Effect, dict[str, Union[float, tuple[float, float]]]] = Field(default_factory=dict)
    stribeck_velocity: float = Field(0.1, gt=0.0)
    coulomb_velocity: float = Field(0.01, gt=0.0)
    held_velocity: float = Field(0.02, gt=0.0)
