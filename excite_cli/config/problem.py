"""The ``optimize`` problem: the YAML file, validated once at load (pydantic). Sections follow the
pipeline: robot, trajectory, limits, constraints, optimizer, sequence, output; each field's
docstring is its description with its unit (``excite schema``, the config reference)."""

from __future__ import annotations

import math
from typing import Literal, Optional, Union

from pydantic import Field, PositiveFloat, field_serializer, field_validator, model_validator

from excite_cli.config.base import (
    MAX_FINE,
    MAX_GRID,
    MAX_HARMONICS,
    MAX_SEED,
    MAX_WORKERS,
    SCHEDULER_ADDRESS,
    ConfigFile,
    FieldProblem,
    Fraction,
    PerJoint,
    Section,
)
from excite_cli.config.constraints import ConstraintsConfig
from excite_cli.config.effects import EffectsConfig
from excite_cli.config.rehearsal import RehearsalConfig
from excite_cli.criteria import NAMES, criterion_record


class RobotConfig(Section):
    """URDF or MJCF, floating or fixed base, active and locked joints, joint ranges, home posture."""

    urdf: str
    """URDF or MJCF file (relative to the config file), or with `source: example-robot-data` a path in its robots."""
    source: Literal["file", "example-robot-data"] = "file"
    """Where `urdf` is found: `file` or `example-robot-data`."""
    package_dirs: list[str] = Field(default_factory=list)
    """Folders (relative to the config file) that hold the packages the URDF's `package://` meshes name."""
    floating_base: bool = False
    """Load with a free-flyer root joint, held fixed at the identity pose (humanoids)."""
    active_joints: list[str] = Field(min_length=1)
    """The n joints that move; their torques are the regressor rows."""
    locked_joints: dict[str, float] = Field(default_factory=dict)
    """Values of held joints [rad or m]; every joint not active is held, at 0 unless given."""
    joint_ranges: dict[str, tuple[float, float]] = Field(default_factory=dict)
    """{joint: [lower, upper]} [rad or m]: a range for joints the file gives none (continuous), or narrower than its."""
    home_posture: dict[str, float] = Field(default_factory=dict)
    """Posture the starts oscillate about [rad] (0 where not given), clipped into the limits."""
    base_wrench_rows: bool = False
    """Also use the 6 base-wrench rows (robots with foot force sensors); needs `floating_base`."""


class TrajectoryConfig(Section):
    """Fourier series (Eq. 50) and sampling: harmonics N, ω [rad/s], cost samples and period [s],
    constraint grid [s]; boundary conditions (``rest``: q̇ = q̈ = 0 at both ends, ``periodic``: Eq. 50
    as it is) and whether both ends are at the home posture."""

    harmonics: int = Field(10, ge=1, le=MAX_HARMONICS)
    """Harmonics N of the Fourier series (Eq. 50): α has n × (2N + 1) coefficients."""
    base_frequency: float = Field(math.pi / 4, gt=0.0)
    """ω of Eq. 50 [rad/s]: N ω × constraint_period ≤ π/2 and ω × duration ≥ π/2."""
    cost_samples: int = Field(40, ge=1, le=MAX_GRID)
    """Instants T whose regressors are stacked in C (Eq. 3)."""
    cost_period: float = Field(0.2, gt=0.0)
    """Time between cost samples [s]; the duration is cost_samples × cost_period."""
    constraint_period: float = Field(0.02, gt=0.0)
    """Time step [s] of the constraint grid over the duration."""
    boundary: Literal["rest", "periodic"] = "rest"
    """`rest`: q̇ = q̈ = 0 at both ends; `periodic`: Eq. 50 as it is."""
    ends_at_home: bool = False
    """Also q(0) = q(duration) = robot.home_posture (no transitions needed)."""

    @property
    def duration(self) -> float:
        """Length of the trajectory [s]: cost_samples × cost_period."""
        return self.cost_samples * self.cost_period


class LimitsConfig(Section):
    """Joint limits (Eq. 51): position margin [rad], velocity [rad/s], acceleration [rad/s²], check
    refinement; joint torques [Nm] (``urdf``: the URDF's effort limits, a scale factor of those, or
    {joint: Nm}; none by default); the fraction of its torque limit each joint (or the joints named)
    must reach somewhere in the motion (none by default)."""

    position_margin: PerJoint = 0.0
    """Distance kept from the URDF's position limits [rad or m], ≥ 0, one value or {joint: value} (others 0)."""
    velocity: Optional[PerJoint] = None
    """|q̇| bound [rad/s], one value or {joint: value}; default the URDF's."""
    acceleration: PerJoint
    """|q̈| bound [rad/s²], one value or {joint: value} (URDFs have none)."""
    check_refinement: int = Field(10, ge=10, le=1000)
    """The fine re-check grid is this many times finer than the constraint grid."""
    torque: Optional[Union[Literal["urdf"], PositiveFloat, dict[str, PositiveFloat]]] = None
    """|τ| bound [Nm]: `urdf` (its effort limits), a factor of those [1], or {joint: Nm}; none by default."""
    min_torque_use: Optional[Union[Fraction, dict[str, Fraction]]] = None
    """Fraction [1] of its torque limit each joint (or each joint named) reaches somewhere in the motion."""


class OptimizerConfig(Section):
    """Solver settings: method (:mod:`excite_cli.search.solvers`), objective, iterations, the solver's own
    tolerance and the first-order optimality tolerance a restart must meet to count as converged
    (:mod:`excite_cli.search.kkt`), seed, restarts, the random starts screened for
    ``screen_iterations`` before the best ``restarts`` continue (``starts``, default: no
    screening), the runs the kept restart continues by until it converges (``polish_rounds``), and
    where restarts run (``workers`` local processes, default the machine's cores; or a Dask
    ``scheduler`` address: a run stops after ``worker_wait`` seconds without any worker)."""

    @property
    def screened(self) -> int:
        """Starts screened before the best ``restarts`` continue; 0 without screening."""
        return self.starts if self.starts is not None and self.starts > self.restarts else 0

    @property
    def planned_iterations(self) -> int:
        """Solver iterations one sequential iteration runs at most (all starts and restarts, and the kept
        restart's polish rounds)."""
        screen = min(self.screen_iterations, self.max_iterations)
        runs = (
            self.screened * screen + self.restarts * (self.max_iterations - screen)
            if self.screened
            else self.restarts * self.max_iterations
        )
        return runs + self.polish_rounds * self.max_iterations

    def scaling_of(self, objective: str) -> str:
        """The regressor ``objective``'s criterion is taken of (``none``: C, ``urdf``: C L): ``scaling``,
        or the criterion's own (:attr:`~excite_cli.criteria.record.CriterionRecord.scaling`) when
        ``scaling`` is not set.

        Raises:
            ExciteError: an unknown objective.
        """
        return self.scaling or criterion_record(objective).scaling

    method: Literal["SLSQP", "trust-constr", "ipopt"] = "SLSQP"
    """The solver: `SLSQP`, `trust-constr` or `ipopt`."""
    objective: Literal[NAMES] = "log_trace_inverse"
    """The criterion minimized, one record each in excite_cli/criteria (what each rewards: docs, how it works)."""
    scaling: Optional[Literal["none", "urdf"]] = None
    """`none`: of C (the paper's); `urdf`: of C L (independent of the base columns); default: the criterion's own."""
    max_iterations: int = Field(200, ge=1, le=100_000)
    """Solver iterations per restart at most (a restart stops earlier once it meets optimality_tolerance)."""
    tolerance: float = Field(1e-6, gt=0.0)
    """The solver's own tolerance [1] (SLSQP ftol, trust-constr gtol, IPOPT tol)."""
    optimality_tolerance: float = Field(1e-3, gt=0.0)
    """Scaled KKT residual [1] at or below which a restart counts as converged."""
    seed: int = Field(0, ge=0, le=MAX_SEED)
    """Seed of the random feasible starts."""
    restarts: int = Field(3, ge=1, le=1000)
    """Solver runs per iteration; the best end point is kept."""
    starts: Optional[int] = Field(None, ge=1, le=10_000)
    """Screening: this many starts run screen_iterations, the best `restarts` go on (default: none)."""
    screen_iterations: int = Field(30, ge=1, le=100_000)
    """Solver iterations of each screened start."""
    polish_rounds: int = Field(3, ge=0, le=100)
    """Runs of max_iterations the kept restart continues by until converged (stalled cond, sigma_min: +1 smoothed)."""
    time_budget: float = Field(1800.0, gt=0.0, le=604_800.0)
    """Wall time [s] an iteration may spend, a safety net: its solver runs stop there (stop: time budget)."""
    workers: Optional[int] = Field(None, ge=1, le=MAX_WORKERS)
    """Local processes the restarts run in (default: the machine's cores)."""
    scheduler: Optional[str] = None
    """A Dask scheduler address ([tcp:// or tls://]host:port) to run the restarts on instead."""
    worker_wait: float = Field(120.0, gt=0.0, le=86_400.0)
    """Seconds [s] a run on `scheduler` waits without any worker before it stops."""

    @field_serializer("scaling")
    def _resolved_scaling(self, _value: Optional[str]) -> str:
        return self.scaling_of(self.objective)  # what the run used, so the stored config runs the same again

    @field_validator("scheduler")
    @classmethod
    def _address(cls, value: Optional[str]) -> Optional[str]:
        if value is not None and not SCHEDULER_ADDRESS.match(value):
            raise ValueError("expected a Dask scheduler address host:port, e.g. tcp://10.0.0.5:8786")
        if value is not None and not 1 <= int(value.rpartition(":")[2]) <= 65535:
            raise ValueError(f"port {value.rpartition(':')[2]} is out of range; expected 1 to 65535")
        return value


#: The noise a design may be for: σ [Nm] (a nano-newton-metre to a mega-newton-metre) and ρ [1] (0 to
#: ten times the torque), so that the rows' weights and their squares stay finite.
NOISE_RANGES = {"absolute": (1e-9, 1e6, " Nm"), "relative": (0.0, 10.0, "")}


class NoiseConfig(Section):
    """The torque noise the design is for (:mod:`excite_cli.design.noise`): per joint an absolute
    part σ [Nm] and a part ρ [1] relative to the torque; each regressor row weighs 1/√(σ_j² + ρ_j² τ_j(t)²)."""

    absolute: PerJoint = 0.1
    """σ_j [Nm], one value or {joint: Nm}: the torque reading's own noise (an identify report as prior gives its)."""
    relative: PerJoint = 0.0
    """ρ_j [1], one value or {joint: value}: noise growing with the torque, as a motor current's (0.02: 2 %)."""

    @model_validator(mode="after")
    def _in_range(self) -> "NoiseConfig":
        for name, (low, high, unit) in NOISE_RANGES.items():
            given = getattr(self, name)
            for joint, value in given.items() if isinstance(given, dict) else [(None, given)]:
                if not low <= value <= high:
                    at = f" for joint '{joint}'" if joint else ""
                    raise ValueError(f"{name}: {value:g}{at} is out of range; expected {low:g} to {high:g}{unit}")
        return self


class RandomBaselineConfig(Section):
    """``compare-random``: pool size and seed of the random candidates."""

    pool_size: int = Field(300, ge=1, le=100_000)
    """Feasible random candidates compare-random draws."""
    seed: int = Field(1, ge=0, le=MAX_SEED)
    """Seed of the candidates."""


class SequenceConfig(Section):
    """Sequential generation (Sec. IV-B): iterations and optional prior data file (Eq. 41)."""

    iterations: int = Field(3, ge=1, le=1000)
    """Sequential trajectories, each stacking the earlier ones as prior data C₀ (Eq. 41)."""
    prior: Optional[str] = None
    """HDF5 file of prior data C₀: an excite result or a file with /regressor (rows × b), or none."""
    replay: bool = True
    """Where an earlier motion beats every restart, restart from it and from the earlier motions' mean; false: never."""


class Problem(ConfigFile):
    """An ``optimize`` problem: the whole YAML file, validated."""

    robot: RobotConfig
    """The robot."""
    trajectory: TrajectoryConfig = TrajectoryConfig()
    """The Fourier trajectory and its sampling."""
    limits: LimitsConfig
    """Joint limits (Eq. 51) and torque limits."""
    constraints: ConstraintsConfig = ConstraintsConfig()
    """Balance, self-collision and world constraints (optional)."""
    effects: EffectsConfig = EffectsConfig()
    """Friction, armature, offsets and coupled motors to design for, beside the base parameters."""
    optimizer: OptimizerConfig = OptimizerConfig()
    """The solver and its starts."""
    sequence: SequenceConfig = SequenceConfig()
    """Sequential generation (Sec. IV-B)."""
    noise: Optional[NoiseConfig] = None
    """The torque noise the rows are weighed by; none: the hedge (for cond, every row the same; README)."""
    random_baseline: RandomBaselineConfig = RandomBaselineConfig()
    """compare-random's candidates."""
    rehearsal: RehearsalConfig = RehearsalConfig()
    """The lab's controller, as `excite rehearse` plays the export in MuJoCo."""
    output: str = "results/excite.h5"
    """Path of the HDF5 result (relative to the working directory)."""

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
