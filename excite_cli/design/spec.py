"""A design resolved once: what an excitation is built from, as values.

    config ─► resolve(problem) ─► DesignSpec ─► build_design(spec) ─► Excitation

(:func:`~excite_cli.design.resolve.resolve`, :func:`~excite_cli.design.excitation.build_design`).

The config's sections a design needs (as values) and everything derived from the robot's file and the
report files (the base parameters, the effect columns, the scaling frame, the measured prior's
weights) are resolved once, in the main process, and held by a frozen, picklable record; the main
process and every worker (a local pool or a Dask cluster) build their
:class:`~excite_cli.design.excitation.Excitation` from that record, so a value changed in memory
(``dataclasses.replace(spec, scaled_frame=…)``) reaches every process, and no worker computes a base of
its own. The record's arrays are read-only.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from excite_cli.config import (
    ConstraintsConfig,
    LimitsConfig,
    NoiseConfig,
    OptimizerConfig,
    RobotConfig,
    SequenceConfig,
    TrajectoryConfig,
)
from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.effect_columns import EffectColumns
from excite_cli.stored.design_model import MeasuredPrior


@dataclass(frozen=True)
class ConfigText:
    """The config a design was resolved from, as a result file stores it.

    Attributes:
        effective: the validated config as YAML, every default filled in (what the run used).
        original: the file's own text.
        path: where the file was read from ("" for a config made in memory).
    """

    effective: str
    original: str
    path: str


@dataclass(frozen=True)
class DesignSpec:
    """What one excitation design is built from, resolved once (:func:`~excite_cli.design.resolve.resolve`).

    Attributes:
        robot, trajectory, limits, constraints, optimizer, sequence, noise: the config's sections
            (``noise`` None: none declared and no hedge; :func:`~excite_cli.design.resolve.resolve` puts
            the hedge there where the criterion takes it, ``hedged``).
        folder: the config file's folder, which relative paths in it are resolved from (None: the
            working directory).
        config: the config's text, as the result file stores it.
        base: the robot's base parameters (Eq. 2).
        effects: the effect columns designed for beside the base columns (``effects``), or None.
        scaled_frame: L (b+e, b+e), read-only: C L is the regressor in a basis that does not depend on
            the choice of base columns (:func:`~excite_cli.design.information.scaled_frame`), each
            effect column scaled by its typical magnitude (:meth:`EffectColumns.magnitudes`).
        measured: how the rows of ``sequence.prior`` weigh when it is an identify report
            (:class:`~excite_cli.stored.design_model.MeasuredPrior`), or None.
        hedged: ``noise`` is the hedge for noise nobody declared
            (:func:`~excite_cli.design.noise.hedged_noise`: no ``noise`` section, no measured prior).
    """

    robot: RobotConfig
    trajectory: TrajectoryConfig
    limits: LimitsConfig
    constraints: ConstraintsConfig
    optimizer: OptimizerConfig
    sequence: SequenceConfig
    noise: NoiseConfig | None
    folder: Path | None
    config: ConfigText
    base: BaseParameters
    effects: EffectColumns | None
    scaled_frame: np.ndarray
    measured: MeasuredPrior | None
    hedged: bool = False

    def __post_init__(self) -> None:
        frame = np.array(self.scaled_frame, dtype=float)
        frame.flags.writeable = False
        object.__setattr__(self, "scaled_frame", frame)

    @property
    def columns(self) -> int:
        """b + e: the regressor's columns, base parameters then effect columns."""
        return self.base.count + (self.effects.count if self.effects else 0)


def needs_collision(ccfg: ConstraintsConfig) -> bool:
    """Whether the robot needs its collision geometry for the constraints ``ccfg``: capsules, the soles'
    contact points."""
    return bool(ccfg.self_collision or ccfg.environment or ccfg.zmp or (ccfg.com and ccfg.com.support_links))
