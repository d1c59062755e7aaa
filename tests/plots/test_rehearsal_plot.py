"""The rehearsal's picture: the tracking error per iteration, and for a standing robot the centre of
pressure inside the support polygon; a PNG written whole."""

from conftest import made_rehearsal
from PIL import Image

from excite_cli.plots.rehearsal import plot_rehearsal


def test_a_standing_robot_gets_its_balance_panel_beside_the_tracking(tmp_path):
    standing = Image.open(plot_rehearsal(tmp_path / "s.png", made_rehearsal()))
    arm = Image.open(plot_rehearsal(tmp_path / "a.png", made_rehearsal(standing=False)))
    assert standing.size[0] > 1.8 * arm.size[0] and standing.size[1] == arm.size[1]
