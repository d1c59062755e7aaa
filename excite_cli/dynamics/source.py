"""A robot's file behind one record: whatever its format (URDF, MJCF; an SRDF beside a URDF for its
named states), the rest of excite asks the same few questions of it, as pinocchio's parsers all end in
one ``Model`` and MuJoCo's compiler in one ``MjSpec``:

- :meth:`RobotSource.model`: pinocchio's model, with a free-flyer root joint when floating;
- :meth:`RobotSource.geometry`: its collision geometry;
- :meth:`RobotSource.couplings`: the joints that follow another (a ``<mimic>``, a joint equality);
- :meth:`RobotSource.check`: what no model of the file can be (before pinocchio reads it);
- :meth:`RobotSource.named_states`: postures the file names (an SRDF's ``group_state``, an MJCF's
  ``<key>``);
- :meth:`RobotSource.free_root`: the root's free joint an MJCF declares (a floating base);
- :meth:`RobotSource.angle_rounding`: the largest rounding of a special angle the file writes.

Each format is one subclass (:class:`~excite_cli.dynamics.urdf_source.UrdfSource`,
:class:`~excite_cli.dynamics.mjcf_source.MjcfSource`); :func:`~excite_cli.dynamics.robot_files.open_source`
picks it from the file's root element.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path

import pinocchio as pin

from excite_cli.errors import ExciteError


@dataclass(frozen=True)
class RobotSource(ABC):
    """One robot file (module docstring).

    Attributes:
        path: the file.
        package_dirs: folders its meshes are looked up in (``package://`` names).
    """

    path: Path
    package_dirs: tuple[str, ...] = field(default=())

    @property
    @abstractmethod
    def kind(self) -> str:
        """The format's name in messages: ``URDF`` or ``MJCF``."""

    @abstractmethod
    def model(self, floating: bool = False) -> pin.Model:
        """pinocchio's model of the file, with a free-flyer root joint ``root_joint`` when ``floating``.

        Raises:
            ExciteError: (``robot.urdf``) a file no model can be made of, in one line.
        """

    @abstractmethod
    def geometry(self, model: pin.Model) -> pin.GeometryModel:
        """The collision geometry of the file on ``model`` (built by :meth:`model`).

        Raises:
            ExciteError: (``robot.urdf``) a mesh that cannot be found or read.
        """

    @abstractmethod
    def couplings(self) -> dict[str, tuple[str, str]]:
        """{follower: (leader, how, in words)} of the joints that follow another."""

    @abstractmethod
    def check(self, active: list[str], locked: list[str] = (), physical: bool = True) -> list[str]:
        """What no model of the file can be, for the ``active`` and ``locked`` joints.

        Args:
            physical: refuse a moved body whose inertia no body can have; False: return such bodies'
                problems in words.

        Returns:
            The moved bodies' inertias no body can have, in words (empty with ``physical``).

        Raises:
            ExciteError: what :func:`~excite_cli.dynamics.urdf_checks.check_urdf` or a coupling check
                refuses.
        """

    @abstractmethod
    def named_states(self) -> dict[str, dict[str, float]]:
        """{state name: {joint: value [rad or m]}} of the postures the file (or its SRDF) names, 1-DoF
        joints only, in the file's order; empty when it names none."""

    @property
    def states_file(self) -> Path | None:
        """The file :meth:`named_states` reads (the robot's own file, unless a format says otherwise)."""
        return self.path

    def with_srdf(self, srdf: Path) -> "RobotSource":
        """This source with its named postures from the SRDF ``srdf``.

        Raises:
            ExciteError: (``srdf``) a format whose states an SRDF does not name (an MJCF has keyframes).
        """
        raise ExciteError("srdf", f"names the states of a URDF; {self.path.name} is an {self.kind}", str(srdf))

    def free_root(self) -> str | None:
        """The name of the free joint of the file's root body (an MJCF floating base), or None."""
        return None

    def angle_rounding(self) -> float:
        """Largest rounding [rad] of a right (or 15°) angle the file writes (0: full precision)."""
        return 0.0


def apply_joint_ranges(model: pin.Model, ranges: dict[str, tuple[float, float]], file_name: str) -> None:
    """Set the position limits of the joints ``ranges`` names ({joint: (lower, upper)} [rad or m]).

    Raises:
        ExciteError: (``robot.joint_ranges.<joint>``) an unknown or multi-DoF joint, lower ≥ upper, or a
            range reaching past the file's own limits.
    """
    for name, (lower, upper) in ranges.items():
        where = f"robot.joint_ranges.{name}"
        if not model.existJointName(name) or model.joints[model.getJointId(name)].nq != 1:
            raise ExciteError(where, f"'{name}' is not a 1-DoF joint of {file_name}")
        k = model.idx_qs[model.getJointId(name)]
        lo, hi = model.lowerPositionLimit[k], model.upperPositionLimit[k]
        if not lower < upper:
            raise ExciteError(where, f"[{lower:g}, {upper:g}] is empty", [lower, upper], "lower < upper")
        if lower < lo or upper > hi:
            raise ExciteError(
                where,
                f"[{lower:g}, {upper:g}] reaches past the limits in {file_name}, [{lo:g}, {hi:g}]",
                [lower, upper],
                "a range inside the file's (it narrows a joint's range, or gives one to a joint without)",
            )
        model.lowerPositionLimit[k], model.upperPositionLimit[k] = lower, upper
