"""The identification data: every run's samples low-passed in parallel (regressor, effect columns
and τ through the same filter, Gautier 1997) and decimated, stacked with rows by instant, then joint."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.identification.effects import Term, effect_columns
from excite_cli.identification.measured.preprocessing import Samples


@dataclass(frozen=True)
class Dataset:
    """Stacked, parallel-filtered and decimated samples: rows ordered by instant, then joint.

    Attributes:
        regressor: (N·n, b) base regressor Y_B (Eq. 3).
        tau: (N·n,) measured torques [Nm].
        time: (N,) [s]; run: (N,) index of the run of each instant.
        blocks: effect columns by :class:`Term`, (N, k) each, on that term's joint's rows (a coupled
            term's on each of its joints' rows, times the joint's weight in its coupling).
    """

    regressor: np.ndarray
    tau: np.ndarray
    time: np.ndarray
    run: np.ndarray
    blocks: dict[Term, np.ndarray]

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.tau.size // self.time.size

    @property
    def joint(self) -> np.ndarray:
        """(N·n,) joint index of each row."""
        return np.tile(np.arange(self.n), self.time.size)

    def joint_rows(self, instants: np.ndarray, joint: int, terms: list[Term]) -> np.ndarray:
        """(len(instants), b + Σk) the rows of the model [Y_B, ``terms``] of one joint at ``instants``
        (indices of ``time``): the base regressor's, then each term's columns on that joint's row."""
        n = self.n
        return np.column_stack(
            [self.regressor[instants * n + joint]] + [self.blocks[t][instants] * t.rows(n)[joint] for t in terms]
        )

    def block(self, term: Term) -> np.ndarray:
        """(N·n, k) columns of ``term``: nonzero only on its joints' rows."""
        cols, weights = self.blocks[term], term.rows(self.n)
        out = np.zeros((self.tau.size, cols.shape[1]))
        for j in term.joints:
            out[j :: self.n] = weights[j] * cols
        return out

    def with_load_columns(self, base_parameters: np.ndarray, terms: list[Term]) -> "Dataset":
        """The dataset with the two-stage ``load_coulomb`` blocks: abs(τ_rigid) times the Coulomb
        block of the same joint, τ_rigid = Y_B φ_B with the base parameters (b,) of a first, rigid-body
        fit (the product of the filtered signals stands for the filtered product: both vary slowly
        at the cut-off). ``terms``: the ``load_coulomb`` terms to add."""
        rigid = np.abs(self.regressor @ base_parameters).reshape(-1, self.n)
        extra = {t: rigid[:, t.joint : t.joint + 1] * self.blocks[Term("coulomb", t.joint)] for t in terms}
        return Dataset(self.regressor, self.tau, self.time, self.run, {**self.blocks, **extra})


def fit_instants(role: str, count: int, blocks: int) -> np.ndarray:
    """(count,) which decimated instants of a run are for fitting: all (``fit``), none
    (``validation``), or the even ones of ``blocks`` contiguous time blocks (``blocks``)."""
    if role == "fit":
        return np.ones(count, dtype=bool)
    if role == "validation":
        return np.zeros(count, dtype=bool)
    return np.minimum((np.arange(count) * blocks) // max(count, 1), blocks - 1) % 2 == 0


def run_offset_columns(run: int, fitted: list[int], count: int, columns: int) -> np.ndarray:
    """(count, columns) offset columns of the instants of ``run``: the indicator of its place among
    the ``fitted`` runs, or 1/columns in every column for a run the fit never saw (the mean offset)."""
    row = np.zeros(columns)
    if run in fitted:
        row[fitted.index(run)] = 1.0
    else:
        row[:] = 1.0 / columns
    return np.broadcast_to(row, (count, columns))


def fit_position_range(samples: list[Samples], blocks: int) -> np.ndarray:
    """(n, 2) the lowest and highest q [rad] of each joint over the fit instants of ``samples`` (as
    the fit sees them: filtered and decimated; see :func:`fit_instants`), the range the guard of the
    position-dependent effects holds them to (:func:`effect_columns`); (−inf, inf) without fit
    instants (:func:`build_datasets` refuses such data)."""
    lo, hi = np.full(len(samples[0].q), np.inf), np.full(len(samples[0].q), -np.inf)
    for s in samples:
        mask = fit_instants(s.role, s.filter.kept(s.time.size), blocks)
        if mask.any():
            for j, q in enumerate(s.q):
                seen = s.filter.decimate(q)[mask]
                lo[j], hi[j] = min(lo[j], seen.min()), max(hi[j], seen.max())
    unseen = lo > hi
    return np.column_stack([np.where(unseen, -np.inf, lo), np.where(unseen, np.inf, hi)])


def _run_columns(
    s: Samples,
    index: int,
    terms: list[Term],
    fitted: list[int],
    offsets: int,
    coulomb_velocity: float,
    q_range: np.ndarray | None,
):
    """Each term's columns of one run, filtered and decimated (offsets: indicator or mean columns;
    position effects guarded by ``q_range`` (n, 2) [rad]; coupled terms in their motor coordinate,
    first), one term at a time, joint by joint:
    yields (term, columns). A joint's full-rate signals are released once its terms are done (the
    samples are used up)."""
    kept = s.filter.kept(s.time.size)
    for t in (t for t in terms if t.coupling is not None):  # motor coordinates: before any joint is released
        coordinate = [sum(t.coupling[j] * x[j] for j in t.joints) for x in (s.q, s.qd, s.qdd)]
        yield t, s.filter.decimate(effect_columns(t.effect, *coordinate, coulomb_velocity, t.shape))
    for j in range(len(s.q)):
        for t in (t for t in terms if t.coupling is None and t.joint == j):
            yield (
                t,
                (
                    run_offset_columns(index, fitted, kept, offsets)
                    if t.kind.per_run
                    else s.filter.decimate(
                        effect_columns(
                            t.effect,
                            s.q[j],
                            s.qd[j],
                            s.qdd[j],
                            coulomb_velocity,
                            t.shape,
                            q_range=None if q_range is None else tuple(q_range[j]),
                        )
                    )
                ),
            )
        s.q[j] = s.qd[j] = s.qdd[j] = None


def _regressor_chunks(robot: Robot, X: np.ndarray, s: Samples, payload: np.ndarray | None):
    """The run's base regressor rows (k, n·b) and the torque (k, n) [Nm] of a known payload (or None),
    computed at the run's rate, filtered and decimated chunk by chunk: yields (first kept sample,
    rows, payload torque)."""
    n, b = robot.n_joints, X.shape[1]

    def values(lo: int, hi: int) -> np.ndarray:
        Y = robot.regressor_stack(*s.states(lo, hi))
        rows = (Y @ X).reshape(-1, n * b)
        return rows if payload is None else np.hstack([rows, (Y @ payload).reshape(-1, n)])

    for start, chunk in s.filter.chunks(values, s.time.size):
        yield start, chunk[:, : n * b], None if payload is None else chunk[:, n * b :]


def build_datasets(
    robot: Robot,
    base: BaseParameters,
    samples: list[Samples],
    terms: list[Term],
    coulomb_velocity: float,
    blocks: int,
    payloads: list[np.ndarray | None] | None = None,
    split: bool = True,
    offset_runs: int | None = None,
    q_range: np.ndarray | None = None,
    sources: list[int] | None = None,
) -> tuple[Dataset, Dataset, list[int]]:
    """The fit and validation datasets: regressor, the effect columns of ``terms`` and torques of the
    samples, each low-passed by its run's filter in parallel and decimated (so the filtered τ still
    equals the filtered columns × φ), split by :func:`fit_instants`. Written straight into
    preallocated arrays, the base regressor chunk by chunk: memory is the decimated data once.
    ``samples`` is emptied as the runs are used. Two-stage terms are left out (see
    :meth:`Dataset.with_load_columns`). Without ``split`` every instant is validation data (the fit
    dataset is empty) and offsets are the mean of ``offset_runs`` fitted runs. ``payloads``: per
    run, the standard parameters (p,) of a known payload (see
    :func:`~excite_cli.identification.measured.payload.payload_parameters`) or None; its torque Y π is
    filtered and decimated with the regressor and taken out of τ. ``q_range``: (n, 2) [rad], the
    fit data's q range per joint (see :func:`fit_position_range`) that guards the position-dependent
    effects, or None (no guard). ``sources``: per sample, the run it is part of (the pieces of a
    recording cut at its gaps are one run: one offset, one index in ``Dataset.run``); default each
    sample its own run.

    Returns:
        fit, validation and the indices of the runs with fit instants (the offsets' columns).

    Raises:
        ExciteError: nothing left for fitting or for validation.
    """
    n, b = robot.n_joints, base.count
    masks = [fit_instants(s.role if split else "validation", s.filter.kept(s.time.size), blocks) for s in samples]
    sizes = {True: sum(int(m.sum()) for m in masks), False: sum(int((~m).sum()) for m in masks)}
    if split and (not sizes[True] or not sizes[False]):
        raise ExciteError("data.runs", "need data for fitting and for validation (roles fit/validation, or blocks)")
    sources = list(range(len(samples))) if sources is None else list(sources)
    fitted = sorted({sources[k] for k, m in enumerate(masks) if m.any()}) if split else []
    offsets = len(fitted) if split else max(offset_runs or 1, 1)
    terms = list(dict.fromkeys(t for t in terms if not t.kind.two_stage))
    width = {t: offsets if t.kind.per_run else len(t.kind.coefficients) for t in terms}
    out = {
        side: {
            "Y": np.empty((size, n * b)),
            "tau": np.empty((size, n)),
            "time": np.empty(size),
            "run": np.empty(size, dtype=int),
            "blocks": {t: np.empty((size, width[t])) for t in terms},
        }
        for side, size in sizes.items()
    }
    at = {True: 0, False: 0}
    for index, mask in enumerate(masks):
        s = samples.pop(0)
        rows = {side: np.flatnonzero(mask == side) for side in (True, False)}
        where = {side: slice(at[side], at[side] + rows[side].size) for side in (True, False)}
        tau = s.tau
        time = s.time[s.filter.trim : s.time.size - s.filter.trim : s.filter.step]
        for side in (True, False):
            out[side]["tau"][where[side]], out[side]["time"][where[side]] = tau[rows[side]], time[rows[side]]
            out[side]["run"][where[side]] = sources[index]
        for start, Y, load in _regressor_chunks(
            robot, base.composition_matrix, s, payloads[index] if payloads else None
        ):
            part = mask[start : start + Y.shape[0]]
            for side in (True, False):
                first = at[side] + int(np.searchsorted(rows[side], start))  # this side's rows before the chunk
                count = int(np.count_nonzero(part == side))
                out[side]["Y"][first : first + count] = Y[part == side]
                if load is not None:
                    out[side]["tau"][first : first + count] -= load[part == side]
        for t, columns in _run_columns(
            s, sources[index], terms, fitted, offsets, coulomb_velocity, q_range
        ):  # releases the run's signals
            for side in (True, False):
                out[side]["blocks"][t][where[side]] = columns[rows[side]]
        for side in (True, False):
            at[side] += rows[side].size
    fit, val = (
        Dataset(o["Y"].reshape(-1, b), o["tau"].ravel(), o["time"], o["run"], o["blocks"])
        for o in (out[True], out[False])
    )
    return fit, val, fitted
