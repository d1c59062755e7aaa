"""The physically consistent fit of one model, with every joint's rotor a body of its own.

A geared joint's rotor inertia (armature) is a body like the links: the consistent fit holds one, ≥ 0,
for every joint whose armature the model's effects do not already hold, whether or not the effect
search added it (Wensing, Kim, Slotine 2017 identify rotors beside the links the same way):

- where it regroups with a link's inertia in the base parameters (a serial arm's first joints), as a
  rotor a of :class:`~excite_cli.identification.fitting.physical.ConsistentProgram` through R;
- elsewhere, as a column of its own (a_j q̈_j on joint j's row) beside the model's effects.

Without the second kind, a rotor whose column lies mostly in the base parameters' span is held by the
links' inertias wherever the search does not add it (it gains little under least squares, which is
free to bend the base parameters): MuJoCo's UR5 with an elbow armature of 0.1 kg·m² came out with
links 3–4 at −10 % and +8.8 % of their masses. Least squares keeps the search's model: declared on
every joint under least squares, the armature took 1867 % validation error on the real Panda fitted on
its first 20 % (docs/figures.md, "Which fit transfers").
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from excite_cli.dynamics.base_parameters import BaseParameters, rotor_regrouping
from excite_cli.dynamics.robot import Robot
from excite_cli.identification.choice.selection import Selection
from excite_cli.identification.effects import Term, coefficient_names, rotor_terms
from excite_cli.identification.fitting.bodies import last_bodies
from excite_cli.identification.fitting.physical import ConsistentFit, ConsistentProgram


class ConsistentModel:
    """The physically consistent fit of one model [Y_B, ``terms``] on any normal equations of its
    unknowns (all fit data, or one fold's training data): one compiled program with the rotors of the
    module docstring and a payload of its own on every body that carries no other.

    Args:
        terms: the model's terms; selection: the fit data's normal equations and the joints' weights.
        robot, base: the URDF's parameters, bodies and regrouping K.
        offset_runs: the labels of the fitted runs, which name the offsets' columns.

    Attributes:
        model: the model's ``terms``.
        terms: the model's terms, then the rotors with columns of their own (``armature`` terms): the
            unknowns [Y_B, ``terms``] of :meth:`fit`'s normal equations and :meth:`coefficients`.
    """

    def __init__(
        self, terms: list[Term], selection: Selection, robot: Robot, base: BaseParameters, offset_runs: list[str]
    ):
        R, free = rotor_regrouping(robot, base), rotor_terms(robot.n_joints, terms)
        rotors = {robot.joint_names[t.joint]: R[:, t.joint] for t in free if R[:, t.joint].any()}
        self.own = [t for t in free if not R[:, t.joint].any() and t in selection.normal.size]
        self.model, self.terms = list(terms), list(terms) + self.own
        joints = self.joints = robot.joint_names
        names = [f"{name} {t.where(joints)}" for t in self.terms for name in coefficient_names(t, offset_runs)]
        reference = selection.normal.system(selection.weights, self.terms)[0]
        phi, carriers = robot.urdf_parameters(), last_bodies(robot.model)
        self.program = ConsistentProgram(reference, base.regrouping, phi, names, robot.body_names, rotors, carriers)

    def fit(self, G: np.ndarray, c: np.ndarray, rows: int, regularization: float) -> ConsistentFit:
        """The SDP of :class:`ConsistentProgram` on the weighted normal equations G, c (of ``terms``'
        unknowns) of ``rows`` rows; the rotors with columns of their own moved from its effects to its
        rotors (``own_columns``).

        Raises:
            ExciteError: the semidefinite program has no solution.
        """
        fit = self.program.solve(G, c, rows, regularization)
        k = fit.effects.size - len(self.own)  # each armature term has one column
        bound = {f"Ia {self.joints[t.joint]} ≥ 0": f"rotor of {self.joints[t.joint]} ≥ 0" for t in self.own}
        return replace(
            fit,
            active=[bound.get(a, a) for a in fit.active],  # named as the rotors through R are
            effects=fit.effects[:k],
            rotors=np.concatenate([fit.rotors, fit.effects[k:]]),
            rotor_joints=fit.rotor_joints + [self.joints[t.joint] for t in self.own],
            own_columns=np.concatenate([fit.own_columns, np.ones(len(self.own), dtype=bool)]),
        )

    def coefficients(self, G: np.ndarray, c: np.ndarray, rows: int, regularization: float) -> np.ndarray:
        """(b + k,) the fit's base parameters and coefficients in the unknowns of ``terms``."""
        return consistent_model(self.fit(G, c, rows, regularization), [], self.joints)[1]


def consistent_model(fit: ConsistentFit, terms: list[Term], joints: list[str]) -> tuple[list[Term], np.ndarray]:
    """The model a consistent fit predicts with: [Y_B, ``terms``, its rotors with columns of their own]
    and its (b + k,) coefficients [K (φ + P ψ) + R a; θ; a_own].

    Args:
        fit: the fit of the model ``terms`` (its ``effects`` are theirs); joints: (n,) joint names.
    """
    own = [Term("armature", joints.index(j)) for j, o in zip(fit.rotor_joints, fit.own_columns) if o]
    return list(terms) + own, np.concatenate([fit.base, fit.effects, fit.rotors[fit.own_columns]])
