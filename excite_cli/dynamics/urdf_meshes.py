"""The meshes a URDF names: where they are, and the collision geometry loaded from them only after
each found mesh is a regular, readable file of a bounded size. pinocchio hands a mesh to assimp as it
is: a FIFO waits for a writer for ever, a 2 GB STL took 7.4 GB of memory before failing, and a file
that is not a mesh (``file:///etc/passwd``) ends in a traceback.

Names are resolved as ROS and pinocchio do: ``package://pkg/rest`` in each package folder (``pkg``
under it), ``file://`` and absolute paths as they are, a relative path beside the URDF and then in
each package folder. A mesh not found here is left to pinocchio, whose refusal is one line too.
"""

from __future__ import annotations

import os
from pathlib import Path
from xml.etree import ElementTree

import pinocchio as pin

from excite_cli.errors import ExciteError
from excite_cli.inputs import input_file

#: Largest mesh file loaded [bytes] (example-robot-data's largest is 29 MB).
MAX_MESH_BYTES = 200_000_000


def package_folders(urdf: Path, given: list[str]) -> list[str]:
    """The folders ``package://`` names of ``urdf`` are looked up in: ``given``, then for each package
    the URDF names, the folder above the URDF's nearest ancestor of that name (the URDF inside its own
    package), then ``ROS_PACKAGE_PATH``'s.

    Args:
        urdf: the URDF file; given: folders known beforehand (the config's, example-robot-data's).
    """
    try:
        names = {m.get("filename", "") for m in ElementTree.parse(urdf).getroot().iter("mesh")}
    except (ElementTree.ParseError, OSError):
        names = set()
    packages = {n[len("package://") :].split("/")[0] for n in names if n.startswith("package://")}
    folders = list(given)
    for ancestor in Path(urdf).resolve().parents:
        if ancestor.name in packages:
            folders.append(str(ancestor.parent))
    folders += [d for d in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if d]
    return list(dict.fromkeys(folders))


def mesh_path(name: str, urdf: Path, package_dirs: list[str]) -> Path | None:
    """Where the mesh ``name`` (as a URDF's ``<mesh filename>`` writes it) is, or None (module docstring)."""
    if name.startswith("package://"):
        candidates = [Path(d) / name[len("package://") :] for d in package_dirs]
    elif name.startswith("file://"):
        candidates = [Path(name[len("file://") :])]
    elif Path(name).is_absolute():
        candidates = [Path(name)]
    else:
        candidates = [Path(urdf).parent / name] + [Path(d) / name for d in package_dirs]
    return next((p for p in candidates if p.exists()), None)


def check_meshes(urdf: Path, package_dirs: list[str], kind: str = "collision") -> None:
    """Every ``<mesh>`` under a ``<kind>`` element of ``urdf`` is found in ``package_dirs`` (or where its
    path points) and is a regular, readable file of at most :data:`MAX_MESH_BYTES`.

    Raises:
        ExciteError: (``robot.urdf``) naming the link and the mesh, and for a mesh not found, every
            folder looked in.
    """
    try:
        root = ElementTree.parse(urdf).getroot()
    except (ElementTree.ParseError, OSError) as exc:
        raise ExciteError("robot.urdf", f"cannot read {urdf}: {exc}") from None
    for link in root.iter("link"):
        for mesh in (m for element in link.iter(kind) for m in element.iter("mesh")):
            name = mesh.get("filename", "")
            path = mesh_path(name, urdf, package_dirs)
            what = f"link '{link.get('name')}': {kind} mesh {name}"
            if path is None:
                package = name[len("package://") :].split("/")[0] if name.startswith("package://") else ""
                raise ExciteError(
                    "robot.urdf",
                    f"{what} is not found; looked in {', '.join(package_dirs) or 'no folder'} "
                    "(robot.package_dirs, beside the URDF, example-robot-data, ROS_PACKAGE_PATH)",
                    name,
                    f"robot.package_dirs: the folder that holds the package '{package}'"
                    if package
                    else "the mesh beside the URDF, where its path points",
                )
            try:
                input_file(path, "robot.urdf", "mesh file")
            except ExciteError as exc:
                raise ExciteError("robot.urdf", f"{what}: {exc.problem}", name, "a mesh file (STL, DAE, OBJ)") from None
            size = path.stat().st_size
            if size > MAX_MESH_BYTES:
                raise ExciteError(
                    "robot.urdf",
                    f"{what} is {size / 1e6:.0f} MB, more than the {MAX_MESH_BYTES / 1e6:.0f} MB excite loads",
                    name,
                    "a smaller (decimated) mesh",
                )


def collision_geometry(model: pin.Model, urdf: Path, package_dirs: list[str]) -> pin.GeometryModel:
    """The collision geometry of ``urdf`` for ``model`` (its meshes checked first, :func:`check_meshes`).

    Raises:
        ExciteError: (``robot.urdf``) a mesh that is not a regular readable file or too large; one
            pinocchio, coal or assimp cannot find or read (their message's first lines).
    """
    check_meshes(urdf, package_dirs)
    try:
        return pin.buildGeomFromUrdf(model, str(urdf), pin.COLLISION, package_dirs=package_dirs)
    except (RuntimeError, ValueError) as exc:
        lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
        said = " ".join(line.removeprefix("message: ") for line in lines if not line.startswith(("From", "in ", "at ")))
        raise ExciteError("robot.urdf", f"cannot load the collision meshes of {urdf.name}: {said[:300]}") from None
