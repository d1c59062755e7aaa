"""The written MJCF checked by MuJoCo itself: the file is loaded with MuJoCo and its inverse dynamics
(``mj_inverse``) is run on the validation runs' q, q̇, q̈, then compared with excite's prediction of
the same model on the same samples, and with the measured torques.

- **Rigid body, armature and viscous friction** (MuJoCo's friction loss off): MuJoCo's torque
  against excite's Y(q, q̇, q̈) X φ_B + the written armature and viscous terms, at every sample of the
  runs (full rate): equal to the written numbers' precision.
- **Coulomb friction**: MuJoCo holds it as ``frictionloss``, a soft constraint whose force in inverse
  dynamics opposes q̈ + b q̇ (b from the constraint's ``solreffriction``) and saturates at
  ±frictionloss once the joint moves, while excite's is F_c tanh(q̇/v_c). They are compared where
  both are saturated with the same sign; the share of samples where they differ (near velocity
  reversals) is reported, and both models' validation errors say what the difference costs.
- **Validation error**: MuJoCo's torques low-passed and decimated like excite's regressor (parallel
  filtering), on the validation instants, against the measured torques, as the report's error.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError
from excite_cli.identification.choice.consistent_model import consistent_model
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import effect_columns
from excite_cli.identification.fitting.dataset import fit_instants
from excite_cli.identification.fitting.least_squares import predict, torque_errors
from excite_cli.identification.measured.gaps import split_at_gaps
from excite_cli.identification.measured.measurements import load_run
from excite_cli.identification.measured.preprocessing import preprocess
from excite_cli.identification.reporting.mjcf_out import MjcfModel, import_mujoco
from excite_cli.identification.reporting.report import Report

STR = h5py.string_dtype()
#: A friction torque counts as saturated at this fraction of frictionloss.
SATURATED = 1.0 - 1e-9
#: MuJoCo's and excite's friction differ where they are further apart than this fraction of it.
DIFFERS = 0.01


@dataclass
class MujocoCheck:
    """MuJoCo's inverse dynamics of the written MJCF against excite's model and the measured torques.

    Attributes:
        rigid: largest |τ_MuJoCo − τ_excite| / largest |τ_excite| without Coulomb friction (rigid
            body, armature, viscous friction) over every sample of the validation runs.
        friction: the same for the Coulomb friction alone, over the (sample, joint) entries where
            both models' are saturated (±frictionloss, ±F_c) with the same sign.
        friction_differs: share [%] of the entries of joints with friction loss where the two
            differ by more than 1 % of F_c (near velocity reversals, where MuJoCo's friction follows
            q̈ + b q̇, its constraint's reference acceleration, and excite's q̇ alone).
        relative_excite: (n,) validation error [%] of excite's consistent model (the report's).
        relative_written: (n,) of excite's model with only the effects the MJCF holds.
        relative_mujoco: (n,) of MuJoCo's model (its torques filtered like excite's regressor).
        unwritten: (effect label, points [%]) by how much the mean validation error rises when that
            unwritten effect is left out of excite's model.
    """

    rigid: float
    friction: float
    friction_differs: float
    relative_excite: np.ndarray
    relative_written: np.ndarray
    relative_mujoco: np.ndarray
    unwritten: list[tuple[str, float]]


class _Replay:
    """MuJoCo's and excite's torques on samples of one run, with the largest deviations seen."""

    def __init__(self, mujoco, path: Path, robot: Robot, X: np.ndarray, x: np.ndarray, model: MjcfModel, v_c: float):
        try:
            self.model = mujoco.MjModel.from_xml_path(str(path))
        except ValueError as exc:
            raise ExciteError("mjcf_out", f"MuJoCo cannot load the written {path}: {exc}") from None
        self.mujoco, self.data = mujoco, mujoco.MjData(self.model)
        self.model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_LIMIT
        joints = [self.model.joint(name) for name in robot.joint_names]
        self.qpos = np.array([j.qposadr[0] for j in joints])
        self.dof = np.array([j.dofadr[0] for j in joints])
        self.robot, self.rigid_x, self.v_c = robot, X @ x, v_c
        self.fields = model.fields
        self.deviation, self.friction, self.scale = 0.0, 0.0, 0.0
        self.entries, self.differs = 0, 0

    def _inverse(self, q, qd, qdd, friction: bool) -> np.ndarray:
        m, d = self.model, self.data
        flag = int(self.mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS)
        m.opt.disableflags = (m.opt.disableflags & ~flag) if friction else (m.opt.disableflags | flag)
        d.qpos[self.qpos], d.qvel[self.dof], d.qacc[self.dof] = q, qd, qdd
        self.mujoco.mj_inverse(m, d)
        return d.qfrc_inverse[self.dof].copy()

    def torques(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """(h, n) MuJoCo's torques [Nm] at the samples (h, n) each, updating the deviations."""
        n = self.robot.n_joints
        excite = (self.robot.regressor_stack(q, qd, qdd) @ self.rigid_x).reshape(-1, n)
        coulomb = np.zeros_like(excite)
        for j, name in enumerate(self.robot.joint_names):
            excite[:, j] += self.fields.get((name, "armature"), 0.0) * qdd[:, j]
            excite[:, j] += self.fields.get((name, "damping"), 0.0) * qd[:, j]
            fc = self.fields.get((name, "frictionloss"), 0.0)
            coulomb[:, j] = fc * effect_columns("coulomb", q[:, j], qd[:, j], qdd[:, j], self.v_c)[:, 0]
        rigid = np.array([self._inverse(*s, friction=False) for s in zip(q, qd, qdd)])
        full = np.array([self._inverse(*s, friction=True) for s in zip(q, qd, qdd)])
        self.scale = max(self.scale, float(np.abs(excite).max()))
        self.deviation = max(self.deviation, float(np.abs(rigid - excite).max()))
        limit = self.model.dof_frictionloss[self.dof]  # as written: MuJoCo's saturates there
        friction, sign = full - rigid, np.sign(coulomb)
        both = (limit > 0) & (np.abs(coulomb) >= SATURATED * limit) & (friction * sign >= SATURATED * limit)
        if both.any():
            self.friction = max(self.friction, float(np.abs(friction - coulomb)[both].max()))
        self.entries += int(np.count_nonzero(limit > 0)) * q.shape[0]
        self.differs += int(np.count_nonzero(np.abs(friction - coulomb) > DIFFERS * limit))
        return full


def check_mjcf(
    problem: IdentifyProblem, report: Report, robot: Robot, base: BaseParameters, model: MjcfModel
) -> MujocoCheck:
    """Load ``model.path`` with MuJoCo and compare its inverse dynamics with excite's model and the
    measured torques on the validation instants of ``problem``'s runs (read and preprocessed again,
    one at a time, with the report's cut-off).

    Raises:
        ExciteError: MuJoCo cannot load the file; the runs cannot be read again.
    """
    consistent, n = report.consistent, robot.n_joints
    replay = _Replay(
        import_mujoco(),
        model.path,
        robot,
        base.composition_matrix,
        consistent.bodies_base,  # the rotors are the joints' armature in the MJCF
        model,
        problem.identification.coulomb_velocity,
    )
    measured, validation = report.validation.tau.reshape(-1, n), report.validation
    predicted = np.empty_like(measured)
    for k, cfg in enumerate(problem.data.runs):
        rows = np.flatnonzero(validation.run == k)
        if rows.size == 0:
            continue
        parts = []  # the run as identify fitted it: piece by piece where it was cut at its gaps (said there)
        for run in split_at_gaps(load_run(cfg, problem.data, robot.joint_names, problem.folder), quiet=True):
            s = preprocess(run, problem.preprocessing, report.cutoff)
            kept = s.filter.kept(s.time.size)
            held_out = ~fit_instants(s.role, kept, problem.data.validation_blocks)
            filtered = np.empty((kept, n))
            for start, chunk in s.filter.chunks(lambda lo, hi: replay.torques(*s.states(lo, hi)), s.time.size):
                filtered[start : start + chunk.shape[0]] = chunk
            parts.append(filtered[held_out])
        predicted[rows] = np.concatenate(parts)
    terms, values = _split(report)
    written = {t for t, _ in model.written}
    kept_terms = [t for t in terms if t in written]
    unwritten = [t for t in terms if t not in written]
    relative = lambda chosen: torque_errors(  # noqa: E731
        measured, predict(validation, np.concatenate([consistent.base, *[values[t] for t in chosen]]), chosen)
    )[2]
    full = relative(terms)
    return MujocoCheck(
        rigid=replay.deviation / max(replay.scale, 1e-300),
        friction=replay.friction / max(replay.scale, 1e-300),
        friction_differs=100.0 * replay.differs / max(replay.entries, 1),
        relative_excite=report.relative_consistent,
        relative_written=relative(kept_terms),
        relative_mujoco=torque_errors(measured, predicted)[2],
        unwritten=[
            (t.label(robot.joint_names), float(relative([u for u in terms if u != t]).mean() - full.mean()))
            for t in unwritten
        ],
    )


def _split(report: Report):
    """The consistent fit's terms in order (its rotors with columns of their own last) and {term: its
    coefficients (k,)}."""
    terms, x = consistent_model(report.consistent, report.selection.terms, report.joints)
    values, k = {}, len(report.base_names)
    for t in terms:
        width = report.validation.blocks[t].shape[1]
        values[t] = x[k : k + width]
        k += width
    return terms, values


def write_mujoco_group(f: h5py.File, model: MjcfModel, check: MujocoCheck, joints: list[str]) -> None:
    """``/mujoco`` of the report: the MJCF's path, joint fields, what it cannot hold (with the points of
    validation error each accounts for) and MuJoCo's check (see :class:`MujocoCheck`)."""
    g = f.create_group("mujoco")
    g.attrs["mjcf"], g.attrs["notes"] = str(model.path), "; ".join(model.notes) or "none"
    g.attrs["rigid_deviation"], g.attrs["friction_deviation"] = check.rigid, check.friction
    g.attrs["description"] = (
        "rigid/friction_deviation: largest |tau_MuJoCo - tau_excite| over the validation runs / largest |tau| "
        "(friction: where both models' Coulomb friction is saturated with one sign); friction_differs_percent: "
        "(sample, joint) entries where they differ by more than 1 % of F_c (velocity reversals)"
    )
    g.attrs["friction_differs_percent"] = check.friction_differs
    for name in ("relative_excite", "relative_written", "relative_mujoco"):
        g.create_dataset(f"validation_{name[9:]}", data=getattr(check, name)).attrs["unit"] = "% per joint"
    fields = np.array(
        [(joint, attribute, value) for (joint, attribute), value in model.fields.items()],
        dtype=[("joint", STR), ("attribute", STR), ("value", "f8")],
    )
    g.create_dataset("joint_fields", data=fields).attrs["units"] = "armature kg·m², damping Nm·s/rad, frictionloss Nm"
    share = dict(check.unwritten)
    unwritten = np.array(
        [(t.label(joints), c, v, why, share[t.label(joints)]) for t, c, v, why in model.unwritten],
        dtype=[("effect", STR), ("coefficient", STR), ("value", "f8"), ("reason", STR), ("points", "f8")],
    )
    g.create_dataset("not_in_mjcf", data=unwritten).attrs["description"] = (
        "effects MuJoCo has no field for; points: rise of the mean validation error [%] without each"
    )
