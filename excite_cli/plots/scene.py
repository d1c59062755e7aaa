"""The motion as a 3D scene in one self-contained HTML file (meshcat's static export, three.js
inside): the robot's collision meshes (pinocchio's meshcat visualizer) moving through the played
samples and the world shapes of ``constraints.environment``. Open it in any browser, no server; the
animation plays on open and from the scene's menu ("Animations")."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import pinocchio as pin

from excite_cli.atomic import MARK, atomic_bytes
from excite_cli.collision.world import ShapeKind, WorldShape
from excite_cli.dynamics.robot import Robot
from excite_cli.errors import ExciteError

#: Side [m] and thickness of the slab that draws a half-space.
SLAB = (3.0, 0.01)


def write_scene(path: Path, robot: Robot, q: np.ndarray, rate: float, shapes: list[WorldShape]) -> Path:
    """An HTML file at ``path`` that plays the postures q (S, n) [rad] at ``rate`` [Hz] on the robot's
    collision meshes, beside ``shapes``.

    Raises:
        ExciteError: meshcat (the ``view`` extra) is not installed.
        CannotWrite: the file cannot be written.
    """
    try:  # 0.7 s to import: only when a scene is written, not at every command's start
        import meshcat
        from meshcat.animation import Animation
    except ImportError:
        raise ExciteError(
            "view", "needs meshcat, which is not installed", expected="the view extra: pip install 'excite[view]'"
        ) from None
    from pinocchio.visualize import MeshcatVisualizer

    with contextlib.redirect_stdout(io.StringIO()):  # the server prints its URL
        viewer = meshcat.Visualizer()
    try:
        model, geometry = robot.model, robot.collision_model
        visualizer = MeshcatVisualizer(model, None, geometry)  # the meshes once, as visuals
        visualizer.initViewer(viewer=viewer)
        visualizer.loadViewerModel(rootNodeName="robot")
        for shape in shapes:
            _draw_shape(viewer[f"world/{shape.name}"], shape)
        data, placements = model.createData(), pin.GeometryData(geometry)
        nodes = [visualizer.getViewerNodeName(g, pin.GeometryType.VISUAL) for g in geometry.geometryObjects]
        animation = Animation(default_framerate=rate)
        for k, posture in enumerate(q):
            configuration = robot.q_reference.copy()
            configuration[robot.q_idx] = posture
            if k == 0:  # the scene before the animation starts (and in a viewer that does not play it)
                visualizer.display(configuration)
            pin.forwardKinematics(model, data, configuration)
            pin.updateGeometryPlacements(model, data, geometry, placements)
            with animation.at_frame(viewer, k) as frame:
                for node, placement in zip(nodes, placements.oMg):
                    frame[node].set_transform(placement.homogeneous)
        viewer.set_animation(animation, play=True, repetitions=0)
        html = viewer.static_html()
    finally:
        viewer.window.server_proc.kill()
        viewer.window.server_proc.wait()
    return atomic_bytes(path, f"<!-- {MARK} view -->\n{html}".encode("utf-8"))


def _draw_shape(node, shape: WorldShape) -> None:
    """A world shape in grey: a thin slab for a half-space, a box, a sphere, a capsule as a cylinder
    with two spheres."""
    import meshcat.geometry as mg
    import meshcat.transformations as tf

    material = mg.MeshLambertMaterial(color=0x999999, opacity=0.6, transparent=True)
    if shape.kind is ShapeKind.BOX:
        node.set_object(mg.Box(list(shape.size)), material)
        node.set_transform(pin.SE3(shape.rotation, shape.start).homogeneous)
        return
    if shape.kind is ShapeKind.HALF_SPACE:
        side, thick = SLAB
        node.set_object(mg.Box([side, side, thick]), material)
        rotation = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), shape.end).matrix()
        node.set_transform(pin.SE3(rotation, shape.start - shape.end * thick / 2).homogeneous)
        return
    node["a"].set_object(mg.Sphere(shape.radius), material)
    node["a"].set_transform(tf.translation_matrix(shape.start))
    if shape.kind is ShapeKind.SPHERE:
        return
    node["b"].set_object(mg.Sphere(shape.radius), material)
    node["b"].set_transform(tf.translation_matrix(shape.end))
    axis = shape.end - shape.start
    node["body"].set_object(mg.Cylinder(float(np.linalg.norm(axis)), shape.radius), material)
    rotation = pin.Quaternion.FromTwoVectors(np.array([0.0, 1.0, 0.0]), axis / np.linalg.norm(axis)).matrix()
    node["body"].set_transform(pin.SE3(rotation, (shape.start + shape.end) / 2).homogeneous)
