"""The identification data: every run's samples low-passed in parallel (regressor, effect columns
and τ through the same filter, Gautier 1997) and decimated, stacked with rows by instant, then joint."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from excite_cli.base_parameters import BaseParameters
from excite_cli.config import IdentificationConfig
from excite_cli.identification.effects import COEFFICIENTS, TWO_STAGE, effect_columns
from excite_cli.identification.preprocessing import Samples
from excite_cli.robot import Robot

EFFECTS = tuple(COEFFICIENTS)


@dataclass(frozen=True)
class Dataset:
    """Stacked, parallel-filtered and decimated samples: rows ordered by instant, then joint.

    Attributes:
        regressor: (N·n, b) base regressor Y_B (Eq. 3).
        tau: (N·n,) measured torques [Nm].
        time: (N,) [s]; run: (N,) index of the run of each instant.
        blocks: effect columns by (effect, joint index), (N, k) each, on that joint's rows.
    """

    regressor: np.ndarray
    tau: np.ndarray
    time: np.ndarray
    run: np.ndarray
    blocks: dict[tuple[str, int], np.ndarray]

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.tau.size // self.time.size

    @property
    def joint(self) -> np.ndarray:
        """(N·n,) joint index of each row."""
        return np.tile(np.arange(self.n), self.time.size)

    def block(self, effect: str, j: int) -> np.ndarray:
        """(N·n, k) columns of ``effect`` on joint j: nonzero only on joint j's rows."""
        cols = self.blocks[(effect, j)]
        out = np.zeros((self.tau.size, cols.shape[1]))
        out[j :: self.n] = cols
        return out

    def with_load_columns(self, base_parameters: np.ndarray) -> "Dataset":
        """The dataset with the two-stage ``load_coulomb`` blocks: abs(τ_rigid) times the Coulomb
        block, τ_rigid = Y_B φ_B with the base parameters (b,) of a first, rigid-body fit (the product
        of the filtered signals stands for the filtered product: both vary slowly at the cut-off)."""
        rigid = np.abs(self.regressor @ base_parameters).reshape(-1, self.n)
        extra = {("load_coulomb", j): rigid[:, j:j + 1] * self.blocks[("coulomb", j)] for j in range(self.n)}
        return Dataset(self.regressor, self.tau, self.time, self.run, {**self.blocks, **extra})

    def select(self, mask: np.ndarray) -> "Dataset":
        """The instants where ``mask`` (N,) is true."""
        rows = np.repeat(mask, self.n)
        return Dataset(self.regressor[rows], self.tau[rows], self.time[mask], self.run[mask],
                       {key: cols[mask] for key, cols in self.blocks.items()})


def build_dataset(robot: Robot, base: BaseParameters, samples: list[Samples], cfg: IdentificationConfig) -> Dataset:
    """Regressor, candidate effect columns and torques of the samples, each low-passed by its run's
    filter in parallel and decimated (so the filtered τ still equals the filtered columns × φ)."""
    n, b = robot.n_joints, base.count
    X = base.composition_matrix
    parts = []
    for index, s in enumerate(samples):
        # the base regressor at the run's rate is (T·n, b): computed, filtered and decimated in chunks
        Y = s.filter.decimate_chunks(lambda lo, hi: (robot.regressor_stack(s.q[lo:hi], s.qd[lo:hi], s.qdd[lo:hi]) @ X)
                                     .reshape(-1, n * b), s.time.size)
        blocks = {
            (e, j): s.filter.decimate(effect_columns(e, s.q[:, j], s.qd[:, j], s.qdd[:, j], cfg.coulomb_velocity,
                                                     cfg.stribeck_velocity, cfg.held_velocity))
            for e in EFFECTS if e not in TWO_STAGE for j in range(n)
        }
        time = s.time[s.filter.trim : s.time.size - s.filter.trim : s.filter.step]
        parts.append((Y.reshape(-1, b), s.filter.decimate(s.tau).ravel(), time, np.full(time.size, index), blocks))
    return Dataset(
        np.vstack([p[0] for p in parts]),
        np.concatenate([p[1] for p in parts]),
        np.concatenate([p[2] for p in parts]),
        np.concatenate([p[3] for p in parts]),
        {key: np.vstack([p[4][key] for p in parts]) for key in parts[0][4]},
    )
