"""Configuration: the ``optimize`` problem's sections (:mod:`~excite_cli.config.problem`), its constraint
sections (:mod:`~excite_cli.config.constraints`) and what every config shares
(:mod:`~excite_cli.config.base`), validated once at load (pydantic)."""

from excite_cli.config.base import (
    COULOMB_VELOCITY,
    MAX_FINE,
    MAX_GRID,
    MAX_HARMONICS,
    MAX_SEED,
    MAX_WORKERS,
    ConfigFile,
    FieldProblem,
    Fraction,
    PerJoint,
    Section,
    effective_yaml,
    resolve_path,
)
from excite_cli.config.constraints import (
    CapsuleConfig,
    ComConfig,
    ConstraintsConfig,
    EnvironmentConfig,
    SelfCollisionConfig,
    WorldShapeConfig,
    ZmpConfig,
)
from excite_cli.config.effects import EffectsConfig, MotorConfig
from excite_cli.config.problem import (
    LimitsConfig,
    NoiseConfig,
    OptimizerConfig,
    Problem,
    RandomBaselineConfig,
    RobotConfig,
    SequenceConfig,
    TrajectoryConfig,
)

__all__ = [
    "COULOMB_VELOCITY",
    "ConfigFile",
    "MAX_FINE",
    "MAX_GRID",
    "MAX_HARMONICS",
    "MAX_SEED",
    "MAX_WORKERS",
    "CapsuleConfig",
    "ComConfig",
    "ConstraintsConfig",
    "EffectsConfig",
    "EnvironmentConfig",
    "FieldProblem",
    "Fraction",
    "LimitsConfig",
    "MotorConfig",
    "NoiseConfig",
    "OptimizerConfig",
    "PerJoint",
    "Problem",
    "RandomBaselineConfig",
    "RobotConfig",
    "Section",
    "SelfCollisionConfig",
    "SequenceConfig",
    "TrajectoryConfig",
    "WorldShapeConfig",
    "ZmpConfig",
    "effective_yaml",
    "resolve_path",
]
