"""A robot that can be: bodies and joints a model cannot have are refused by name, before pinocchio."""

import pytest
from conftest import GOOD, PENDULUM

from excite_cli.dynamics.urdf_checks import check_urdf
from excite_cli.errors import ExciteError


def _urdf(tmp_path, **fields):
    path = tmp_path / "robot.urdf"
    path.write_text(PENDULUM.format(**{**GOOD, "mimic": "", **fields}))
    return path


def test_the_pendulum_is_a_robot_that_can_be(tmp_path):
    check_urdf(_urdf(tmp_path), ["hinge"])


@pytest.mark.parametrize(
    "fields, active, expected",
    [
        ({"mass": "-1.5"}, ["hinge"], "arm"),  # a negative mass
        ({"mass": "nan"}, ["hinge"], "arm"),  # not a number
        ({"izz": "0.5"}, ["hinge"], "arm"),  # principal moments breaking the triangle inequality
        ({"lower": "3.0"}, ["hinge"], "hinge"),  # lower limit above the upper one
        ({"tip_ixx": "1.0"}, ["hinge"], "tip"),  # the tip moves with the hinge: its inertia too
    ],
)
def test_a_body_or_joint_that_cannot_be_is_named(tmp_path, fields, active, expected):
    with pytest.raises(ExciteError, match=expected):
        check_urdf(_urdf(tmp_path, **fields), active)
