"""Problem configuration: the YAML file, validated once at load (pydantic).

Sections follow the pipeline: robot, trajectory, limits, optimizer, sequence, output.
Every field is documented in README.md ("Config reference") with its unit and default.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import Literal, Optional, Union

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from excite_cli.errors import ExciteError, FileNotFound

PerJoint = Union[float, dict[str, float]]

#: Largest number of harmonics N (the paper uses 5-10; the memory grows with N × grid instants).
MAX_HARMONICS = 100
#: Largest number of cost samples and of constraint-grid instants.
MAX_GRID = 20000


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
    """Joint limits (Eq. 51): position margin [rad], velocity [rad/s], acceleration [rad/s²], check refinement."""

    position_margin: float = Field(0.0, ge=0.0)
    velocity: Optional[PerJoint] = None
    acceleration: PerJoint
    check_refinement: int = Field(10, ge=10)


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


class ConstraintsConfig(Section):
    """Optional balance and self-collision constraints."""

    com: Optional[ComConfig] = None
    self_collision: Optional[SelfCollisionConfig] = None


class OptimizerConfig(Section):
    """Solver settings: method (:mod:`excite_cli.optimization.solvers`), objective, iterations, the solver's own
    tolerance and the first-order optimality tolerance a restart must meet to count as converged
    (:mod:`excite_cli.optimization.optimality`), seed, restarts, the random starts screened for
    ``screen_iterations`` before the best ``restarts`` continue (``starts``, default: no
    screening), and where restarts run (``workers`` local processes, default the machine's cores;
    or a Dask ``scheduler`` address)."""

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
    objective: Literal["log_cond", "cond", "log_det", "sigma_min"] = "log_cond"
    max_iterations: int = Field(200, ge=1)
    tolerance: float = Field(1e-6, gt=0.0)
    optimality_tolerance: float = Field(1e-3, gt=0.0)
    seed: int = Field(0, ge=0)
    restarts: int = Field(3, ge=1)
    starts: Optional[int] = Field(None, ge=1)
    screen_iterations: int = Field(30, ge=1)
    workers: Optional[int] = Field(None, ge=1)
    scheduler: Optional[str] = None


class RandomBaselineConfig(Section):
    """``compare-random``: pool size and seed of the random candidates."""

    pool_size: int = Field(300, ge=1)
    seed: int = Field(1, ge=0)


class SequenceConfig(Section):
    """Sequential generation (Sec. IV-B): iterations and optional prior data file (Eq. 41)."""

    iterations: int = Field(3, ge=1)
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
        if self.trajectory.constraint_period > self.trajectory.duration:
            raise ValueError(
                "trajectory.constraint_period must not exceed the trajectory duration "
                f"cost_samples × cost_period = {self.trajectory.duration:g} s"
            )
        instants = self.trajectory.duration / self.trajectory.constraint_period
        if instants > MAX_GRID:
            raise ValueError(
                f"trajectory.constraint_period: the constraint grid would have {instants:.0f} instants "
                f"(at most {MAX_GRID}; the fine check has {self.limits.check_refinement}× more)"
            )
        return self

    def resolve(self, path: str) -> Path:
        """A path from the config, relative to the config file's folder (absolute paths kept)."""
        p = Path(path).expanduser()
        if p.is_absolute() or self.source_path is None:
            return p
        return self.source_path.parent / p


def with_overrides(config: BaseModel, overrides: dict[str, object]) -> BaseModel:
    """A validated copy of ``config`` with dotted fields replaced (command-line options), e.g.
    ``{"sequence.iterations": 2, "optimizer.seed": 5}``; None values are left out. The original is
    not changed, so what ran is the copy (stored as the effective config).

    Raises:
        ExciteError: an override is not valid for its field (the message names the field).
    """
    data = config.model_dump()
    for dotted, value in overrides.items():
        if value is None:
            continue
        *parents, last = dotted.split(".")
        functools.reduce(dict.__getitem__, parents, data)[last] = value
    try:
        copy = type(config).model_validate(data)
    except ValidationError as error:
        raise _validation_error(Path("command line"), error) from None
    for name in ("source_path", "source_text"):
        if name in type(config).model_fields:
            setattr(copy, name, getattr(config, name))
    return copy


def effective_yaml(config: BaseModel) -> str:
    """The validated config as YAML, every default filled in: what a run actually used."""
    return yaml.safe_dump(config.model_dump(mode="json"), sort_keys=False, allow_unicode=True)


def _validation_error(path: Path, error: ValidationError) -> ExciteError:
    first = error.errors()[0]
    field = ".".join(str(part) for part in first["loc"]) or "(top level)"
    message = first["msg"].removeprefix("Value error, ")
    if first["type"] == "missing":
        message = "is required but missing"
    elif first["type"] == "extra_forbidden":
        message = "is not a known field (check its spelling; see README 'Config reference')"
    else:
        message = f"{message} (got {first.get('input')!r})"
    more = len(error.errors()) - 1
    suffix = f" (+{more} more problem{'s' if more > 1 else ''})" if more else ""
    return ExciteError(field, f"{message}{suffix}", first.get("input"), source=path)


class _UniqueKeyLoader(yaml.SafeLoader):
    """YAML's safe loader, refusing a key given twice in one mapping (YAML lets the last one win silently)."""

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(None, None, f"duplicate key '{key}'", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


def load_problem(path: str | Path, kind: type[BaseModel] = Problem):
    """Read and validate a YAML file as a :class:`Problem` (or another config ``kind``).

    Args:
        path: the YAML file.
        kind: :class:`Problem`, :class:`IdentifyProblem` or :class:`SimulationConfig`.

    Returns:
        The validated config, with ``source_path`` and ``source_text`` set where it has them.

    Raises:
        ExciteError: missing file, malformed YAML or an invalid field; the message names the field.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFound("config", path, "config file")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ExciteError("config", f"{path} is not a text (UTF-8) file", path, "a YAML config") from None
    except OSError as exc:
        raise ExciteError("config", f"cannot read {path}: {exc.strerror}", path) from None
    try:
        raw = yaml.load(text, Loader=_UniqueKeyLoader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ExciteError("config", f"{path}: malformed YAML{where}: {getattr(exc, 'problem', exc)}", path) from None
    if not isinstance(raw, dict):
        raise ExciteError(
            "config",
            f"{path}: {'empty file' if raw is None else 'not a mapping'}",
            path,
            "a mapping of sections (see README 'Config reference')",
        )
    try:
        problem = kind.model_validate(raw)
    except ValidationError as exc:
        raise _validation_error(path, exc) from None
    if hasattr(problem, "source_path"):
        problem.source_path = path.resolve()
        problem.source_text = text
    return problem
