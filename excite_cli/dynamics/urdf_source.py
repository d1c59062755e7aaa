"""A robot described in URDF, as pinocchio reads it, with the postures its SRDF names
(:mod:`~excite_cli.dynamics.srdf`).

A URDF's continuous joints are read as revolute joints without a range (pinocchio would give each
two configuration coordinates, cos and sin, which no Fourier series of an angle moves):
``robot.joint_ranges`` gives such a joint the range it may move in, and narrows any other's.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pinocchio as pin

from excite_cli.dynamics.source import RobotSource
from excite_cli.dynamics.srdf import srdf_beside, srdf_states
from excite_cli.dynamics.urdf_checks import check_urdf, urdf_couplings
from excite_cli.dynamics.urdf_meshes import collision_geometry
from excite_cli.dynamics.urdf_rounding import angle_rounding
from excite_cli.errors import ExciteError


def _continuous_as_revolute(path: Path) -> tuple[str, list[str]]:
    """The URDF text at ``path`` with each continuous joint made revolute, and those joints' names."""
    root = ElementTree.parse(path).getroot()
    names = []
    for joint in root.iter("joint"):
        if joint.get("type") == "continuous":
            joint.set("type", "revolute")
            limit = joint.find("limit")
            limit = ElementTree.SubElement(joint, "limit") if limit is None else limit
            limit.attrib.update({k: limit.get(k, "0") for k in ("effort", "velocity")}, lower="0", upper="0")
            names.append(joint.get("name"))
    return ElementTree.tostring(root, encoding="unicode"), names


@dataclass(frozen=True)
class UrdfSource(RobotSource):
    """A URDF (:class:`~excite_cli.dynamics.source.RobotSource`), with ``srdf`` the SRDF given for its
    named postures (None: the one beside it, :func:`~excite_cli.dynamics.srdf.srdf_beside`, if any)."""

    srdf: Path | None = None

    @property
    def states_file(self) -> Path | None:
        """The SRDF whose group states are the named postures: ``srdf``, else the one beside the URDF."""
        return self.srdf if self.srdf is not None else srdf_beside(self.path)

    @property
    def kind(self) -> str:
        return "URDF"

    def model(self, floating: bool = False) -> pin.Model:
        """pinocchio's model, continuous joints revolute with limits ±inf (module docstring).

        Raises:
            ExciteError: (``robot.urdf``) a file urdfdom or pinocchio cannot make a model of (an unknown
                joint type, a missing attribute), in one line.
        """
        root = [pin.JointModelFreeFlyer()] if floating else []
        try:
            text, continuous = _continuous_as_revolute(self.path)
            model = pin.buildModelFromXML(text, *root) if continuous else pin.buildModelFromUrdf(str(self.path), *root)
        except (RuntimeError, ValueError, ElementTree.ParseError) as exc:
            raise ExciteError("robot.urdf", f"cannot read {self.path}: {' '.join(str(exc).split())[:300]}") from None
        for name in continuous:
            k = model.idx_qs[model.getJointId(name)]
            model.lowerPositionLimit[k], model.upperPositionLimit[k] = -np.inf, np.inf
        return model

    def geometry(self, model: pin.Model) -> pin.GeometryModel:
        """See :func:`~excite_cli.dynamics.urdf_meshes.collision_geometry`."""
        return collision_geometry(model, self.path, list(self.package_dirs))

    def couplings(self) -> dict[str, tuple[str, str]]:
        """The URDF's ``<mimic>`` joints (:func:`~excite_cli.dynamics.urdf_checks.urdf_couplings`)."""
        return urdf_couplings(ElementTree.parse(self.path).getroot())

    def check(self, active: list[str], locked: list[str] = (), physical: bool = True) -> list[str]:
        """See :func:`~excite_cli.dynamics.urdf_checks.check_urdf`."""
        return check_urdf(self.path, list(active), physical, list(locked))

    def with_srdf(self, srdf: Path) -> "UrdfSource":
        """This URDF with the named postures of ``srdf``."""
        return replace(self, srdf=srdf)

    def named_states(self) -> dict[str, dict[str, float]]:
        """The group states of :attr:`states_file` (:func:`~excite_cli.dynamics.srdf.srdf_states`); none
        without an SRDF."""
        srdf = self.states_file
        return srdf_states(srdf) if srdf is not None else {}

    def angle_rounding(self) -> float:
        """See :func:`~excite_cli.dynamics.urdf_rounding.angle_rounding`."""
        return angle_rounding(self.path)
