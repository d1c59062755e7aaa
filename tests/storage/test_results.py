"""The optimize result file: units on its datasets."""

import h5py
from conftest import UR5, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.storage.results import read_table


def test_result_datasets_carry_their_units(tmp_path):
    data = {
        **UR5,
        "trajectory": {**UR5["trajectory"], "harmonics": 3, "cost_samples": 20, "cost_period": 0.4},
        "optimizer": {"max_iterations": 5, "restarts": 1},
        "sequence": {"iterations": 1},
    }
    out = tmp_path / "u.h5"
    assert CliRunner().invoke(app, ["optimize", str(write_config(tmp_path, data)), "-o", str(out)]).exit_code == 0
    with h5py.File(out) as f:
        units = {name: f["iterations/1"][name].attrs["unit"] for name in ("alpha", "time", "q", "qd", "qdd")}
    assert units == {"alpha": "rad", "time": "s", "q": "rad", "qd": "rad/s", "qdd": "rad/s^2"}
    table, wall = read_table(out)
    assert list(table["iteration"]) == [1] and table["cond_stacked"][0] > 1.0 and wall > 0.0
