"""The home posture search: when none holds, the best posture found is written and the problem names
the joints it moved, what binds there and what to change."""

from conftest import GOOD, PENDULUM

from excite_cli.drafting.home_posture import HOME_ROUNDS
from excite_cli.drafting.starting_config import draft_config
from excite_cli.dynamics.robot_files import open_source


def test_no_home_posture_names_the_joints_it_chose_what_binds_and_what_to_change(tmp_path):
    """The pendulum held away from hanging (lower limit 0.5 rad) with 0.01 Nm efforts: gravity exceeds
    the torque limits at every posture at rest."""
    urdf = tmp_path / "weak.urdf"
    urdf.write_text(
        PENDULUM.format(**{**GOOD, "mimic": "", "lower": "0.5"})
        .replace('effort="20"', 'effort="0.01"')
        .replace('effort="5"', 'effort="0.01"')
    )
    draft = draft_config(
        {"urdf": "weak.urdf", "source": "file"}, open_source(urdf, [str(tmp_path)]), None, tmp_path / "weak.yaml"
    )
    assert f"in {HOME_ROUNDS} rounds with the 2 active joints hinge, tip_joint;" in draft.problem
    assert "clearance" not in draft.problem  # no capsule: no clearance to speak of
    assert "at the best posture found (written), limits.torque fails:" in draft.problem  # what binds, not a guess
    assert draft.problem.endswith("loosen that constraint's field, or move fewer joints (e.g. one arm's)")
    assert draft.assumptions["robot.home_posture"] == f"FIX FIRST: {draft.problem}"
    home = draft.config["robot"]["home_posture"]
    assert list(home) == ["hinge", "tip_joint"] and 0.5 <= home["hinge"] <= 2.0  # inside the URDF's range
