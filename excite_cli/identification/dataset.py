"""The identification data: every run's samples low-passed in parallel (regressor, effect columns
and τ through the same filter, Gautier 1997) and decimated, stacked with rows by instant, then joint."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from excite_cli.base_parameters import BaseParameters
from excite_cli.identification.config import IdentificationConfig
from excite_cli.errors import ExciteError
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


def fit_instants(role: str, count: int, blocks: int) -> np.ndarray:
    """(count,) which decimated instants of a run are for fitting: all (``fit``), none
    (``validation``), or the even ones of ``blocks`` contiguous time blocks (``blocks``)."""
    if role == "fit":
        return np.ones(count, dtype=bool)
    if role == "validation":
        return np.zeros(count, dtype=bool)
    return np.minimum((np.arange(count) * blocks) // max(count, 1), blocks - 1) % 2 == 0


def build_datasets(robot: Robot, base: BaseParameters, samples: list[Samples], cfg: IdentificationConfig,
                   blocks: int, effects: set[str] | None = None, split: bool = True) -> tuple[Dataset, Dataset]:
    """The fit and validation datasets: regressor, candidate effect columns and torques of the
    samples, each low-passed by its run's filter in parallel and decimated (so the filtered τ still
    equals the filtered columns × φ), split by :func:`fit_instants`. Written straight into
    preallocated arrays, the base regressor chunk by chunk: memory is the decimated data once.
    ``samples`` is emptied as the runs are used. ``effects``: the effects whose blocks to build
    (default: all that need no first fit). Without ``split`` every instant is validation data (the
    fit dataset is empty).

    Raises:
        ExciteError: nothing left for fitting or for validation.
    """
    n, b = robot.n_joints, base.count
    X = base.composition_matrix
    masks = [fit_instants(s.role if split else "validation", s.filter.kept(s.time.size), blocks) for s in samples]
    sizes = {True: sum(int(m.sum()) for m in masks), False: sum(int((~m).sum()) for m in masks)}
    if split and (not sizes[True] or not sizes[False]):
        raise ExciteError("data.runs: need data for fitting and for validation (roles fit/validation, or blocks)")
    keys = [(e, j) for e in EFFECTS if e not in TWO_STAGE and (effects is None or e in effects) for j in range(n)]
    out = {side: {"Y": np.empty((size, n * b)), "tau": np.empty((size, n)), "time": np.empty(size),
                  "run": np.empty(size, dtype=int), "blocks": {key: np.empty((size, len(COEFFICIENTS[key[0]]))) for key in keys}}
           for side, size in sizes.items()}
    at = {True: 0, False: 0}
    for index, mask in enumerate(masks):
        s = samples.pop(0)
        rows = {side: np.flatnonzero(mask == side) for side in (True, False)}
        where = {side: slice(at[side], at[side] + rows[side].size) for side in (True, False)}
        tau = s.filter.decimate(s.tau)
        time = s.time[s.filter.trim : s.time.size - s.filter.trim : s.filter.step]
        columns = {(e, j): s.filter.decimate(effect_columns(e, s.q[:, j], s.qd[:, j], s.qdd[:, j], cfg.coulomb_velocity,
                                                            cfg.stribeck_velocity, cfg.held_velocity)) for e, j in keys}
        for side in (True, False):
            out[side]["tau"][where[side]] = tau[rows[side]]
            out[side]["time"][where[side]] = time[rows[side]]
            out[side]["run"][where[side]] = index
            for key in keys:
                out[side]["blocks"][key][where[side]] = columns[key][rows[side]]
        del columns
        # the base regressor at the run's rate is (T·n, b): computed, filtered and decimated in chunks
        for start, chunk in s.filter.chunks(lambda lo, hi: (robot.regressor_stack(s.q[lo:hi], s.qd[lo:hi], s.qdd[lo:hi]) @ X)
                                            .reshape(-1, n * b), s.time.size):
            part = mask[start : start + chunk.shape[0]]
            for side in (True, False):
                first = at[side] + int(np.searchsorted(rows[side], start))  # this side's rows before the chunk
                picked = chunk[part == side]
                out[side]["Y"][first : first + picked.shape[0]] = picked
        for side in (True, False):
            at[side] += rows[side].size
    fit, val = (Dataset(o["Y"].reshape(-1, b), o["tau"].ravel(), o["time"], o["run"], o["blocks"]) for o in (out[True], out[False]))
    return fit, val
