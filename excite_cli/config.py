"""Problem configuration: the YAML file, validated once at load (pydantic).

Sections follow the pipeline: robot, trajectory, limits, optimizer, sequence, output.
Every field is documented in README.md ("Config reference") with its unit and default.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Annotated, Literal, Optional, Union

import yaml
from pydantic import BaseModel, ConfigDict, Field, PositiveFloat, field_validator, model_validator

PerJoint = Union[float, dict[str, float]]
#: A fraction in (0, 1).
Fraction = Annotated[float, Field(gt=0.0, lt=1.0)]

#: Largest number of harmonics N (the paper uses 5-10; the memory grows with N × grid instants).
MAX_HARMONICS = 100
#: Largest number of cost samples and of constraint-grid instants.
MAX_GRID = 20000
#: Largest number of instants of the fine re-check (constraint grid × check_refinement).
MAX_FINE = 1_000_000
#: Largest seed (numpy's generators take any; 32 bits is what other tools can repeat).
MAX_SEED = 2**32 - 1
#: A Dask scheduler address: ``[tcp:// or tls://]host:port`` (an IPv6 host in brackets).
SCHEDULER_ADDRESS = re.compile(r"^((tcp|tls)://)?(\[[0-9a-fA-F:]+\]|[\w.-]+):\d{1,5}$")
#: Largest number of local worker processes.
MAX_WORKERS = 256


class FieldProblem(ValueError):
    """A problem a validator finds with one field of a section or of another (``field`` dotted from
    the top of the file), reported under that field instead of the section's."""

    def __init__(self, field: str, problem: str):
        super().__init__(problem)
        self.field, self.problem = field, problem


class Section(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class RobotConfig(Section):
    """URDF, floating or fixed base, active and locked joints, home posture (README: `robot`)."""

    urdf: str = Field(description="URDF path (relative to the config file) or a path inside example-robot-data")
    source: Literal["file", "example-robot-data"] = "file"
    floating_base: bool = False
    active_joints: list[str] = Field(min_length=1)
    locked_joints: dict[str, float] = Field(default_factory=dict)
    home_posture: dict[str, float] = Field(default_factory=dict)
    base_wrench_rows: bool = False


class TrajectoryConfig(Section):
    """Fourier series (Eq. 50) and sampling: harmonics N, ω [rad/s], cost samples and period [s],
    constraint grid [s]; boundary conditions (``rest``: q̇ = q̈ = 0 at both ends, ``periodic``: Eq. 50
    as it is) and whether both ends are at the home posture."""

    harmonics: int = Field(10, ge=1, le=MAX_HARMONICS)
    base_frequency: float = Field(math.pi / 4, gt=0.0)
    cost_samples: int = Field(40, ge=1, le=MAX_GRID)
    cost_period: float = Field(0.2, gt=0.0)
    constraint_period: float = Field(0.02, gt=0.0)
    boundary: Literal["rest", "periodic"] = "rest"
    ends_at_home: bool = False

    @property
    def duration(self) -> float:
        """Length of the trajectory [s]: cost_samples × cost_period."""
        return self.cost_samples * self.cost_period


class LimitsConfig(Section):
    """Joint limits (Eq. 51): position margin [rad], velocity [rad/s], acceleration [rad/s²], check
    refinement; joint torques [Nm] (``urdf``: the URDF's effort limits, a scale factor of those, or
    {joint: Nm}; none by default); the fraction of its torque limit each joint (or the joints named)
    must reach somewhere in the motion (none by default)."""

    position_margin: float = Field(0.0, ge=0.0)
    velocity: Optional[PerJoint] = None
    acceleration: PerJoint
    check_refinement: int = Field(10, ge=10, le=1000)
    torque: Optional[Union[Literal["urdf"], PositiveFloat, dict[str, PositiveFloat]]] = None
    min_torque_use: Optional[Union[Fraction, dict[str, Fraction]]] = None


class ComConfig(Section):
    """Centre-of-mass region (Eq. 52): support links or centre [m], radius [m] or polygon [m]."""

    support_links: list[str] = Field(default_factory=list)
    centre: Optional[tuple[float, float]] = None
    radius: Optional[float] = Field(None, gt=0.0)
    polygon: Optional[list[tuple[float, float]]] = Field(None, min_length=3)

    @model_validator(mode="after")
    def _one_region(self) -> "ComConfig":
        if (self.radius is None) == (self.polygon is None):
            raise ValueError("give exactly one of radius [m] or polygon [[x, y], ...] [m]")
        if bool(self.support_links) == (self.centre is not None):
            raise ValueError("give exactly one of support_links or centre [x, y] [m]")
        return self


class CapsuleConfig(Section):
    """One capsule on a link: radius [m], segment end points in the link frame [m]."""

    link: str
    radius: float = Field(gt=0.0)
    start: tuple[float, float, float]
    end: tuple[float, float, float]


class SelfCollisionConfig(Section):
    """Self-collision (Eq. 53): capsules (``auto`` or given), ignored links, excluded pairs, margin [m]."""

    capsules: Union[Literal["auto"], list[CapsuleConfig]] = "auto"
    ignore_links: list[str] = Field(default_factory=list)
    exclude_pairs: list[tuple[str, str]] = Field(default_factory=list)
    margin: float = Field(0.01, ge=0.0)


class WorldShapeConfig(Section):
    """A shape fixed in the world frame the robot's capsules keep ``margin`` [m] from: a half-space
    (``point`` on its plane, ``normal`` towards the robot's side: a floor, a table top), a sphere
    (``centre``, ``radius``), a capsule (``start``, ``end``, ``radius``) or a box (``centre``, side
    lengths ``size``, turned by ``rpy`` [rad] about x, y, z), all in metres."""

    name: str
    type: Literal["half_space", "sphere", "capsule", "box"]
    point: Optional[tuple[float, float, float]] = None
    normal: Optional[tuple[float, float, float]] = None
    centre: Optional[tuple[float, float, float]] = None
    start: Optional[tuple[float, float, float]] = None
    end: Optional[tuple[float, float, float]] = None
    radius: Optional[float] = Field(None, gt=0.0)
    size: Optional[tuple[PositiveFloat, PositiveFloat, PositiveFloat]] = None
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    margin: float = Field(0.02, ge=0.0)

    @model_validator(mode="after")
    def _fields_of_its_type(self) -> "WorldShapeConfig":
        needs = {
            "half_space": ("point", "normal"),
            "sphere": ("centre", "radius"),
            "capsule": ("start", "end", "radius"),
            "box": ("centre", "size"),
        }
        missing = [f for f in needs[self.type] if getattr(self, f) is None]
        if missing:
            raise ValueError(f"a {self.type} needs {', '.join(missing)}")
        if self.type == "half_space" and not 0.0 < math.hypot(*self.normal) < math.inf:
            raise ValueError("the normal of a half_space must not be zero")
        return self


class EnvironmentConfig(Section):
    """The world around the robot (issue 19): shapes its capsules (``auto``: fitted to the URDF's
    collision meshes, or given) keep away from, minus ``ignore_links``."""

    shapes: list[WorldShapeConfig] = Field(min_length=1)
    capsules: Union[Literal["auto"], list[CapsuleConfig]] = "auto"
    ignore_links: list[str] = Field(default_factory=list)


class ConstraintsConfig(Section):
    """Optional balance, self-collision and world constraints."""

    com: Optional[ComConfig] = None
    self_collision: Optional[SelfCollisionConfig] = None
    environment: Optional[EnvironmentConfig] = None


class OptimizerConfig(Section):
    """Solver settings: method (:mod:`excite_cli.optimization.solvers`), objective, iterations, the solver's own
    tolerance and the first-order optimality tolerance a restart must meet to count as converged
    (:mod:`excite_cli.optimization.optimality`), seed, restarts, the random starts screened for
    ``screen_iterations`` before the best ``restarts`` continue (``starts``, default: no
    screening), and where restarts run (``workers`` local processes, default the machine's cores;
    or a Dask ``scheduler`` address: a run stops after ``worker_wait`` seconds without any worker)."""

    @property
    def screened(self) -> int:
        """Starts screened before the best ``restarts`` continue; 0 without screening."""
        return self.starts if self.starts is not None and self.starts > self.restarts else 0

    @property
    def planned_iterations(self) -> int:
        """Solver iterations one sequential iteration runs at most (all starts and restarts)."""
        screen = min(self.screen_iterations, self.max_iterations)
        return (
            self.screened * screen + self.restarts * (self.max_iterations - screen)
            if self.screened
            else self.restarts * self.max_iterations
        )

    method: Literal["SLSQP", "trust-constr", "ipopt"] = "SLSQP"
    objective: Literal["log_cond", "cond", "log_det", "sigma_min", "log_trace_inverse"] = "log_det"
    scaling: Literal["none", "urdf"] = "none"
    max_iterations: int = Field(200, ge=1, le=100_000)
    tolerance: float = Field(1e-6, gt=0.0)
    optimality_tolerance: float = Field(1e-3, gt=0.0)
    seed: int = Field(0, ge=0, le=MAX_SEED)
    restarts: int = Field(3, ge=1, le=1000)
    starts: Optional[int] = Field(None, ge=1, le=10_000)
    screen_iterations: int = Field(30, ge=1, le=100_000)
    workers: Optional[int] = Field(None, ge=1, le=MAX_WORKERS)
    scheduler: Optional[str] = None
    worker_wait: float = Field(120.0, gt=0.0, le=86_400.0)

    @field_validator("scheduler")
    @classmethod
    def _address(cls, value: Optional[str]) -> Optional[str]:
        if value is not None and not SCHEDULER_ADDRESS.match(value):
            raise ValueError("expected a Dask scheduler address host:port, e.g. tcp://10.0.0.5:8786")
        return value


class RandomBaselineConfig(Section):
    """``compare-random``: pool size and seed of the random candidates."""

    pool_size: int = Field(300, ge=1, le=100_000)
    seed: int = Field(1, ge=0, le=MAX_SEED)


class SequenceConfig(Section):
    """Sequential generation (Sec. IV-B): iterations and optional prior data file (Eq. 41)."""

    iterations: int = Field(3, ge=1, le=1000)
    prior: Optional[str] = None


class Problem(Section):
    """An ``optimize`` problem: the whole YAML file, validated."""

    robot: RobotConfig
    trajectory: TrajectoryConfig = TrajectoryConfig()
    limits: LimitsConfig
    constraints: ConstraintsConfig = ConstraintsConfig()
    optimizer: OptimizerConfig = OptimizerConfig()
    sequence: SequenceConfig = SequenceConfig()
    random_baseline: RandomBaselineConfig = RandomBaselineConfig()
    output: str = "results/excite.h5"

    source_path: Optional[Path] = Field(None, exclude=True)
    source_text: str = Field("", exclude=True)

    @model_validator(mode="after")
    def _grid_fits(self) -> "Problem":
        t, refinement = self.trajectory, self.limits.check_refinement
        if t.constraint_period > t.duration:
            raise FieldProblem(
                "trajectory.constraint_period",
                f"{t.constraint_period:g} s exceeds the trajectory duration "
                f"cost_samples × cost_period = {t.duration:g} s",
            )
        instants = t.duration / t.constraint_period
        if instants > MAX_GRID or instants * refinement > MAX_FINE:
            raise FieldProblem(
                "trajectory.constraint_period",
                f"the constraint grid would have {instants:.0f} instants (at most {MAX_GRID}) and its fine "
                f"check {refinement}× more (at most {MAX_FINE})",
            )
        if t.harmonics * t.base_frequency * t.constraint_period > math.pi / 2:
            raise FieldProblem(
                "trajectory.base_frequency",
                f"the highest harmonic N ω = {t.harmonics * t.base_frequency:g} rad/s has fewer than 4 "
                f"constraint-grid instants per cycle (constraint_period {t.constraint_period:g} s): the limits "
                "could not be checked; expected N ω × constraint_period ≤ π/2",
            )
        if t.base_frequency * t.duration < math.pi / 2:
            raise FieldProblem(
                "trajectory.base_frequency",
                f"{t.base_frequency:g} rad/s gives the {t.duration:g} s trajectory less than a quarter of its "
                "base period, too little to move in; expected ω × cost_samples × cost_period ≥ π/2",
            )
        return self

    @property
    def folder(self) -> Optional[Path]:
        """The config file's folder, which relative paths in it are relative to (None without a file)."""
        return None if self.source_path is None else self.source_path.parent


def resolve_path(path: str, folder: Optional[Path]) -> Path:
    """``path`` relative to ``folder`` (absolute paths, and any path without a folder, kept as given)."""
    p = Path(path).expanduser()
    return p if p.is_absolute() or folder is None else folder / p


def effective_yaml(config: BaseModel) -> str:
    """The validated config as YAML, every default filled in: what a run actually used."""
    return yaml.safe_dump(config.model_dump(mode="json"), sort_keys=False, allow_unicode=True)
