"""HDF5 result files (h5py), readable without excite. Schema in docs/output.md.

The file is rewritten whole after every finished iteration into a temporary file that then replaces
the target (``os.replace`` is atomic), so an interrupted run leaves a valid file with the finished
iterations and never a half-written one.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import h5py
import numpy as np

from excite_cli.design.excitation import Excitation
from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.errors import ExciteError
from excite_cli.h5 import atomic_h5, open_h5, read_strings, write_strings
from excite_cli.search.kkt import Optimality
from excite_cli.search.optimizer import RestartResult
from excite_cli.search.sequence import IterationResult, describe

UNITS = {
    "alpha": "rad",
    "time": "s",
    "q": "rad",
    "qd": "rad/s",
    "qdd": "rad/s^2",
    "regressor": "SI (N·m per parameter unit)",
}


def results_table(results: Sequence[IterationResult]) -> np.ndarray:
    """Table I as a structured array: iteration, cond_own, cond_stacked (on the base and effect columns, the
    paper's), scaled_cond_own, scaled_cond_stacked (cond(C L)) and excitation_own, excitation_stacked
    (ē [N·m]), which do not depend on the choice of base columns (:mod:`excite_cli.design.information`),
    and max_correlation with an earlier iteration (NaN for the first, :mod:`excite_cli.trajectory.similarity`)."""
    fields = ("cond_own", "cond_stacked", "scaled_cond_own", "scaled_cond_stacked", "excitation_own")
    fields += ("excitation_stacked", "max_correlation")
    table = np.zeros(len(results), dtype=[("iteration", "i4")] + [(name, "f8") for name in fields])
    for row, r in zip(table, results):
        row["iteration"] = r.index
        for name in fields:
            row[name] = getattr(r, name)
    return table


def write_result(
    path: Path, excitation: Excitation, results: Sequence[IterationResult], seed: int, attributes: dict | None = None
) -> None:
    """Write (or replace atomically) the result file of a sequential generation.

    Args:
        path: target ``.h5`` file; its folder is created.
        excitation: the problem (robot names, composition matrix, config text).
        results: finished iterations, in order.
        seed: the seed the run used.
        attributes: extra root attributes (e.g. ``method``, ``pool_size``).

    Raises:
        ExciteError: the file cannot be written.
    """
    with atomic_h5(path) as f:
        config = excitation.spec.config
        f.attrs["config"], f.attrs["config_original"], f.attrs["config_path"] = (
            config.effective,
            config.original,
            config.path,
        )
        f.attrs["seed"] = seed
        f.attrs["objective"] = excitation.spec.optimizer.objective
        for name, value in (attributes or {}).items():
            f.attrs[name] = value
        _write_robot(f.create_group("robot"), excitation)
        iterations = f.create_group("iterations")
        for r in results:
            _write_iteration(iterations.create_group(str(r.index)), r)
        table = f.create_dataset("table", data=results_table(results))
        table.attrs["description"] = (
            "Table I: cond of each iteration's regressor and of the stacked regressor on the base columns "
            "(and the effect columns, with effects), "
            "their cond(C L) and excitation e [N m], which do not depend on the base columns, and the largest "
            "correlation of the motion with an earlier iteration's (docs/output.md)"
        )


def _write_robot(group: h5py.Group, excitation: Excitation) -> None:
    robot, base = excitation.robot, excitation.base
    write_strings(group, "joint_names", robot.joint_names)
    write_strings(group, "parameter_names", robot.parameter_names)
    write_strings(group, "base_parameter_names", base.names)
    write_strings(group, "base_independent_parameters", [robot.parameter_names[k] for k in base.independent])
    group.create_dataset("composition_matrix", data=base.composition_matrix).attrs["description"] = (
        "X (p x b): Y_B = Y X (Eq. 2)"
    )
    group.create_dataset("regrouping_matrix", data=base.regrouping).attrs["description"] = "K (b x p): phi_B = K phi"
    group.create_dataset("urdf_base_parameters", data=base.from_standard(robot.urdf_parameters()))
    group.attrs["urdf"] = excitation.spec.robot.urdf
    group.attrs["floating_base"] = excitation.spec.robot.floating_base
    group.attrs["regressor_rows_per_instant"] = robot.n_rows
    if excitation.effects is not None:
        write_strings(group, "effect_names", excitation.effects.names)
        write_strings(group, "effect_units", excitation.effects.units)


def _write_iteration(group: h5py.Group, r: IterationResult) -> None:
    for name in ("alpha", "time", "q", "qd", "qdd", "regressor"):
        group.create_dataset(name, data=getattr(r, name)).attrs["unit"] = UNITS[name]
    group["alpha"].attrs["layout"] = "row j: [q0_j, a_j1..a_jN, b_j1..b_jN] (Eq. 50)"
    for name, series in r.tracks.items():
        group.create_dataset(name, data=series).attrs["unit"] = r.track_units[name]
    group.attrs["cond_own"] = r.cond_own
    group.attrs["cond_stacked"] = r.cond_stacked
    group.attrs["scaled_cond_own"] = r.scaled_cond_own
    group.attrs["scaled_cond_stacked"] = r.scaled_cond_stacked
    group.attrs["excitation_own_Nm"] = r.excitation_own
    group.attrs["excitation_stacked_Nm"] = r.excitation_stacked
    group.attrs["max_violation"] = r.max_violation
    group.attrs["max_correlation"] = r.max_correlation
    correlations = group.create_dataset("correlations", data=np.array(r.correlations, dtype=float))
    correlations.attrs["description"] = "with each earlier iteration's mean-removed q, in order (1: the same motion)"
    group.attrs["wall_time_s"] = r.wall_time_s
    group.attrs["sqp_iterations"] = r.sqp_iterations
    group.attrs["stop"] = str(r.stop)  # a Stop member: its word
    group.attrs["optimizer_message"] = r.best.message if r.best else ""
    for key, value in r.checks.items():
        group.attrs[key] = value
    restarts = group.create_group("restarts")
    restarts.attrs["kept"] = r.best.index if r.best else -1
    for restart in r.restarts:
        _write_restart(restarts.create_group(str(restart.index)), restart)


def _write_restart(group: h5py.Group, r: RestartResult) -> None:
    group.create_dataset("alpha", data=r.alpha).attrs["unit"] = UNITS["alpha"]
    history = group.create_dataset("history", data=r.history)
    history.attrs["columns"] = "objective, largest constraint value g (normalized, > 0 outside)"
    history.attrs["description"] = "one row per solver iteration, at its accepted iterate"
    for name in ("objective", "start_objective", "iterations", "wall_time_s"):
        group.attrs[name] = getattr(r, name)
    for name in ("message", "stop", "end"):  # words (``stop`` and ``end`` are Stop and End members)
        group.attrs[name] = str(getattr(r, name))
    o = r.optimality
    group.attrs.update(
        kkt_residual=o.residual,
        active_constraints=o.active,
        gradient_norm=o.gradient_norm,
        max_constraint=o.max_constraint,
    )


def _read_restart(group: h5py.Group, index: int) -> RestartResult:
    a = group.attrs
    optimality = Optimality(
        float(a["kkt_residual"]), int(a["active_constraints"]), float(a["gradient_norm"]), float(a["max_constraint"])
    )
    return RestartResult(
        index,
        group["alpha"][()],
        float(a["objective"]),
        int(a["iterations"]),
        str(a["message"]),
        float(a["wall_time_s"]),
        float(a["start_objective"]),
        group["history"][()],
        optimality,
        str(a["stop"]),
        str(a["end"]),
    )


def check_base(f: h5py.File, base: BaseParameters, field: str, path: Path) -> None:
    """Refuse a result whose stored base parameters (``/robot/base_parameter_names``) are not ``base``'s.

    Raises:
        ExciteError: (``field``) other base parameters (another robot, joint set or base).
    """
    if "robot/base_parameter_names" in f:
        base.column_order(read_strings(f["robot"], "base_parameter_names"), field, path)


def read_iterations(
    path: Path, excitation: Excitation, prior: np.ndarray | None = None, field: str = "resume"
) -> list[IterationResult]:
    """The finished iterations of a result of the same problem, as :class:`IterationResult` (checks
    recomputed from the stored α, wall time, SQP iterations and message as stored), to resume it.

    Raises:
        ExciteError: missing or unreadable file, or a result of another problem.
    """
    results: list[IterationResult] = []
    with open_h5(path, field) as f:
        if "iterations" not in f:
            raise ExciteError(field, f"{path} is not an excite optimize result (no /iterations)")
        check_base(f, excitation.base, field, path)
        for key in sorted(f["iterations"].keys(), key=int):
            g = f["iterations"][key]
            alpha = g["alpha"][()]
            if alpha.shape != (excitation.robot.n_joints, excitation.trajectory.n_coefficients):
                raise ExciteError(field, f"{path} was made for another problem (alpha shape {alpha.shape})")
            restarts = (
                [_read_restart(g["restarts"][r], int(r)) for r in sorted(g["restarts"].keys(), key=int)]
                if "restarts" in g
                else []
            )
            kept = int(g["restarts"].attrs["kept"]) if "restarts" in g else -1
            results.append(
                describe(excitation, int(key), alpha, prior, float(g.attrs["wall_time_s"]), restarts, results, kept)
            )
    return results


def read_table(path: Path, field: str = "result") -> tuple[np.ndarray, float]:
    """The condition-number table (iteration, cond_own, cond_stacked) of an excite result and the
    summed wall time of its iterations [s].

    Raises:
        ExciteError: missing or unreadable file, or no table in it.
    """
    with open_h5(path, field) as f:
        if "table" not in f or "iterations" not in f:
            raise ExciteError(field, f"{path} is not an excite result (no /table)", path)
        wall = sum(float(g.attrs.get("wall_time_s", 0.0)) for g in f["iterations"].values())
        return f["table"][()], wall


def read_alphas(path: Path) -> list[tuple[int, np.ndarray]]:
    """(k, α (n, 2N+1)) of every iteration of an excite result, in order (whether 2N + 1 is its
    config's, the reader that builds the design checks).

    Raises:
        ExciteError: missing or unreadable file, no iteration in it, or coefficients that are not
            (active joints, 2N + 1) finite numbers of one shape (a damaged file).
    """
    with open_h5(path) as f:
        keys = sorted(f["iterations"].keys(), key=int) if "iterations" in f else []
        if not keys:
            raise ExciteError("result", f"{path} has no finished iteration", path)
        alphas = [(int(k), np.asarray(f["iterations"][k]["alpha"][()], dtype=float)) for k in keys]
        joints = len(read_strings(f["robot"], "joint_names"))
    shape = alphas[0][1].shape
    fourier = len(shape) == 2 and shape[0] == joints and shape[1] % 2 == 1
    for k, alpha in alphas:
        if not fourier or alpha.shape != shape or not np.all(np.isfinite(alpha)):
            raise ExciteError(
                "result", f"{path}: iteration {k} has no valid Fourier coefficients ({joints}, 2N + 1)", path
            )
    return alphas
