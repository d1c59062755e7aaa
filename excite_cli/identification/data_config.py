"""The data section of an ``excite identify`` config: the measured runs, their files' columns, units,
signs, payloads and the motors' transmission (pydantic, validated once at load; each field's
docstring is its description with its unit)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal, Optional, Union

import numpy as np
from pydantic import Field, field_validator, model_validator

from excite_cli.config import Section, resolve_path
from excite_cli.config.effects import MAX_RATIO

Column = Union[Annotated[int, Field(ge=0, strict=True)], str]  # strict: `time: true` is not column 1
#: Highest sample rate [Hz] (of the decimated data, of a simulated run).
MAX_RATE = 100_000.0


class ColumnsConfig(Section):
    """Columns of measured data, in active-joint order, by name or by 0-based position, and the factor
    of any column recorded in other units (SI value = recorded value × factor: encoder counts → rad,
    mA → A, ms → s)."""

    time: Optional[Column] = "time"
    """Time column [s] (name or 0-based position), or null: time is the row index / data.sample_rate."""
    q: list[Column] = Field(min_length=1)
    """Joint position columns [rad], in active-joint order."""
    qd: Optional[list[Column]] = None
    """Joint velocity columns [rad/s], or none: differentiated."""
    qdd: Optional[list[Column]] = None
    """Joint acceleration columns [rad/s²], or none: differentiated."""
    tau: Optional[list[Column]] = None
    """Joint torque columns [Nm] (or current)."""
    current: Optional[list[Column]] = None
    """Motor current columns [A] (or tau), times data.torque_constants."""
    factors: dict[str, float] = Field(default_factory=dict)
    """{column: factor [1]}: SI value = recorded value × factor (counts → rad, mA → A, ms → s)."""

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


#: The heaviest payload a run may declare [kg] (the heaviest industrial arms carry about 2 t).
MAX_PAYLOAD = 10_000.0
#: The farthest a payload's centre of mass may lie from its link [m], and its largest moment of inertia [kg·m²].
MAX_REACH, MAX_INERTIA = 100.0, 1e6
Reach = Annotated[float, Field(ge=-MAX_REACH, le=MAX_REACH)]
Moment = Annotated[float, Field(ge=-MAX_INERTIA, le=MAX_INERTIA)]


class PayloadConfig(Section):
    """A known payload of a run: mass [kg], centre of mass [m] and inertia about it [kg·m²]
    (Ixx, Ixy, Iyy, Ixz, Iyz, Izz) in ``frame`` (default: the link of the last active joint)."""

    mass: float = Field(gt=0.0, le=MAX_PAYLOAD)
    """Mass [kg]."""
    com: tuple[Reach, Reach, Reach] = (0.0, 0.0, 0.0)
    """Centre of mass [m] in `frame`."""
    inertia: tuple[Moment, Moment, Moment, Moment, Moment, Moment] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    """Inertia about the CoM [kg·m²]: Ixx, Ixy, Iyy, Ixz, Iyz, Izz in `frame`."""
    frame: Optional[str] = None
    """The link it is fixed to (default: the link of the last active joint)."""

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
    """One measured run: file, optional crop [s], role (fit, validation or time blocks), a known payload,
    the trajectory it recorded."""

    file: Union[str, list[str]]
    """A data file (CSV, NPZ, MAT, HDF5, ROS bag), or a list of files recorded apart, joined on time."""
    crop: Optional[tuple[float, float]] = None
    """The part of the run used: its start t0 and end t1 [s]."""
    role: Literal["fit", "validation", "blocks"] = "blocks"
    """`fit`, `validation` (never fitted nor seen by the selection) or `blocks` (alternate time blocks)."""
    payload: Optional[PayloadConfig] = None
    """A known payload carried in this run, taken out of τ."""
    trajectory: Optional[str] = None
    """A name for the motion recorded, shared by its runs (default: the file; recordings of one motion found as one)."""

    @property
    def files(self) -> list[str]:
        """The run's file or files, as written."""
        return [self.file] if isinstance(self.file, str) else list(self.file)

    def recording(self, folder: Path | None) -> str:
        """Which recording the run is: its files relative to ``folder``, resolved and joined."""
        return " + ".join(str(resolve_path(f, folder)) for f in self.files)

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
    """Gear ratio N [1] per active joint (not 0): m = R q, R = diag(N) C."""
    coupling: Optional[list[list[float]]] = None
    """Coupling matrix C [1] (n × n, invertible; default identity)."""

    @field_validator("gear_ratios")
    @classmethod
    def _nonzero_ratios(cls, values):
        if any(not (np.isfinite(v) and 1.0 / MAX_RATIO <= abs(v) <= MAX_RATIO) for v in values):
            raise ValueError(
                f"every gear ratio must be finite, {1 / MAX_RATIO:g} to {MAX_RATIO:g} in size (another unit?)"
            )
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
    """The measured runs."""
    columns: Optional[ColumnsConfig] = None
    """The columns of the files (ROS bags: matched by joint name; where every run is a bag, these name its columns)."""
    topic: str = "/joint_states"
    """The sensor_msgs/JointState topic of ROS bags."""
    angle_unit: Literal["rad", "deg"] = "rad"
    """`rad` or `deg`."""
    torque_constants: Optional[list[float]] = None
    """Joint torque per unit of current [Nm/A] per joint (a vendor's gain: may be negative, τ alone flips)."""
    signs: Optional[list[float]] = None
    """1 or −1 [1] per joint, multiplying q, q̇, q̈ and τ (a joint turning the other way than the URDF's)."""
    validation_blocks: int = Field(4, ge=2, le=100)
    """A `blocks` run is cut into this many time blocks: even ones fit, odd ones validate."""
    bad_rows: Literal["error", "drop"] = "error"
    """`error`: a row that cannot be used stops the run; `drop`: such rows are left out and counted."""
    transmission: Optional[TransmissionConfig] = None
    """Gear ratios and coupling of the motors, or none."""
    motor_side: bool = False
    """The columns hold motor angles and motor torques or currents, mapped through the transmission."""
    sample_rate: Optional[float] = Field(None, gt=0.0, le=MAX_RATE)
    """Sample rate [Hz] of files without a time column."""

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
        if values is not None and any(v == 0.0 or not np.isfinite(v) for v in values):
            raise ValueError(
                "every torque constant must be a finite number other than 0 Nm/A (the vendor's gain from "
                "current to joint torque; negative where the vendor's is)"
            )
        if values is not None and any(not 1.0 / MAX_RATIO <= abs(v) <= MAX_RATIO for v in values):
            raise ValueError(
                f"every torque constant must lie within {1 / MAX_RATIO:g} to {MAX_RATIO:g} Nm/A in size (no "
                "motor's is outside: another unit?)"
            )
        return values

    @field_validator("signs")
    @classmethod
    def _plus_or_minus_one(cls, values):
        if values is not None and any(v not in (1.0, -1.0) for v in values):
            raise ValueError("every sign must be 1 or -1")
        return values
