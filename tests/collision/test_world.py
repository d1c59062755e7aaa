"""The world's shapes as the config gives them: each of its kind, a half-space's normal of unit length,
a box turned by its roll, pitch and yaw (pinocchio's convention, R = Rz(y) Ry(p) Rx(r))."""

import numpy as np

from excite_cli.collision.world import ShapeKind, world_shapes
from excite_cli.config import EnvironmentConfig


def test_each_shape_is_of_its_kind_with_a_unit_normal_and_a_turned_box():
    shapes = world_shapes(
        EnvironmentConfig.model_validate(
            {
                "shapes": [
                    {"name": "floor", "type": "half_space", "point": [0, 0, -1], "normal": [0, 3, 4]},
                    {"name": "ball", "type": "sphere", "centre": [1, 2, 3], "radius": 0.5},
                    {"name": "post", "type": "capsule", "start": [0, 0, 0], "end": [0, 0, 1], "radius": 0.1},
                    {"name": "shelf", "type": "box", "centre": [1, 0, 0], "size": [1, 2, 3], "rpy": [0, 0, np.pi / 2]},
                ]
            }
        )
    )
    assert [s.kind for s in shapes] == [ShapeKind.HALF_SPACE, ShapeKind.SPHERE, ShapeKind.CAPSULE, ShapeKind.BOX]
    np.testing.assert_allclose(shapes[0].end, [0, 0.6, 0.8])  # (0, 3, 4) / 5
    assert shapes[1].radius == 0.5 and np.array_equal(shapes[1].start, shapes[1].end)  # a segment of length 0
    np.testing.assert_allclose(shapes[3].rotation @ [1, 0, 0], [0, 1, 0], atol=1e-15)  # yaw π/2 turns x onto y
    assert shapes[3].radius == 0.0 and list(shapes[3].size) == [1, 2, 3]
    assert world_shapes(None) == []
