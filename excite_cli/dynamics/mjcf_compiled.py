"""An MJCF compiled by MuJoCo's own compiler (cached while the file is unchanged), with or without its
meshes, and which XML files are MJCFs."""

from __future__ import annotations

import functools
from pathlib import Path
from xml.etree import ElementTree

from excite_cli.errors import ExciteError


def is_mjcf(path: Path) -> bool:
    """Whether the XML file at ``path`` is an MJCF (its root element is ``<mujoco>``); False for a file
    that is not XML (the URDF reader names that)."""
    try:
        return ElementTree.parse(path).getroot().tag == "mujoco"
    except (ElementTree.ParseError, OSError):
        return False


def _import_mujoco(path: str):
    try:
        import mujoco
    except ImportError:
        raise ExciteError(
            "robot.urdf",
            f"{Path(path).name} is an MJCF, which excite reads with MuJoCo's compiler: MuJoCo is not installed",
            expected="pip install 'excite-cli[mujoco]' (make install has it)",
        ) from None
    return mujoco


def without_meshes(mujoco, path: str):
    """The file's spec with its mesh geoms and mesh assets removed, or None where a body's inertia
    comes from its geoms (no ``<inertial>``, or ``inertiafromgeom="true"``): without the meshes it
    would change."""
    spec = mujoco.MjSpec.from_file(path)
    meshes = [g for g in spec.geoms if g.type == mujoco.mjtGeom.mjGEOM_MESH]
    from_geoms = spec.compiler.inertiafromgeom == mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE
    bodies = {g.parent.name for g in meshes}
    if from_geoms or any(not b.explicitinertial for b in spec.bodies if b.name in bodies):
        return None
    for geom in meshes:
        spec.delete(geom)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    return spec


@functools.lru_cache(maxsize=8)
def _compiled(path: str, mtime: float, meshes: bool = True):
    mujoco = _import_mujoco(path)
    try:
        spec = None if meshes else without_meshes(mujoco, path)
        return spec.compile() if spec is not None else mujoco.MjModel.from_xml_path(path)
    except ValueError as exc:
        problem = f"MuJoCo cannot compile {Path(path).name}: {' '.join(str(exc).split())[:300]}"
        raise ExciteError("robot.urdf", problem) from None


def compiled(path: Path, meshes: bool = True):
    """MuJoCo's ``MjModel`` of the MJCF at ``path`` (cached while the file is unchanged); without
    ``meshes``, compiled with no mesh read where no body's inertia depends on one (mesh geoms are then
    left out: a model for dynamics, not collisions).

    Raises:
        ExciteError: (``robot.urdf``) MuJoCo is not installed, or its compiler refuses the file (a
            missing include or mesh is named by MuJoCo's message).
    """
    return _compiled(str(Path(path).resolve()), Path(path).stat().st_mtime, meshes)


def mjcf_name(mj, kind: str, index: int) -> str:
    """The name of element ``index`` of ``kind`` (``body``, ``joint``, ...) of the compiled ``mj``, or
    ``<kind><index>`` for an unnamed one."""
    return getattr(mj, kind)(index).name or f"{kind}{index}"
