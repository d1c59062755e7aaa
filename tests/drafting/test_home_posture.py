"""The home posture search: when none holds, the message names the joints it moved and what to give."""

import pytest
from conftest import GOOD, PENDULUM

from excite_cli.drafting.home_posture import HOME_ROUNDS
from excite_cli.drafting.starting_config import draft_config
from excite_cli.errors import ExciteError


def test_no_home_posture_names_the_joints_it_chose_and_what_to_give(tmp_path):
    """The pendulum held away from hanging (lower limit 0.5 rad) with 0.01 Nm efforts: gravity exceeds
    the torque limits at every posture at rest."""
    urdf = tmp_path / "weak.urdf"
    urdf.write_text(
        PENDULUM.format(**{**GOOD, "mimic": "", "lower": "0.5"})
        .replace('effort="20"', 'effort="0.01"')
        .replace('effort="5"', 'effort="0.01"')
    )
    with pytest.raises(
        ExciteError,
        match=f"in {HOME_ROUNDS} rounds with the 2 active joints hinge, tip_joint; .*the joints to move named",
    ) as caught:
        draft_config({"urdf": "weak.urdf", "source": "file"}, urdf, [str(tmp_path)], None, tmp_path / "weak.yaml")
    assert "clearance" not in str(caught.value)  # no capsule: no clearance to speak of
    assert "at the best posture found, limits.torque fails:" in str(caught.value)  # what binds, not a guess
