"""A starting config's limits: a joint the URDF gives no range is named."""

import pytest
from conftest import GOOD, PENDULUM

from excite_cli.drafting.starting_config import draft_config
from excite_cli.dynamics.robot_files import open_source
from excite_cli.errors import ExciteError


def test_a_joint_the_urdf_gives_no_range_is_named(tmp_path):
    """The double pendulum of example-robot-data has lower = upper = 0: it was refused as 'position_margin:
    0 rad leaves no range', far from the cause."""
    urdf = tmp_path / "still.urdf"
    urdf.write_text(PENDULUM.format(**{**GOOD, "mimic": "", "lower": "2.0"}))  # upper is 2.0 too
    with pytest.raises(ExciteError, match="the URDF gives hinge no position range"):
        draft_config(
            {"urdf": "still.urdf", "source": "file"}, open_source(urdf, [str(tmp_path)]), ["hinge"], tmp_path / "s.yaml"
        )
