"""`identify` on several trajectories: the spread between them is reported beside the noise-only std,
with the recordings of one trajectory (recorded twice: named by ``data.runs[].trajectory``, or found by
their motion) counted once. The
spread's calibration against its truth: fitting/test_model_error.py."""

import h5py
import numpy as np
import pytest
import yaml
from conftest import CONFIGS
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.identification.data_config import RunConfig

runner = CliRunner()


def _simulated(optimized, folder, seed):
    """The 3 trajectories of ``optimized`` simulated with friction and a spring on joint 2 (the model
    is not given the spring: model error), one run each."""
    folder.mkdir()
    effects = {"sample_rate": 200.0, "periods": 1, "torque_noise": 0.05, "seed": seed}
    effects["effects"] = {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}, "spring": {"panda_joint2": 20.0}}
    (folder / "effects.yaml").write_text(yaml.safe_dump(effects))
    out = runner.invoke(app, ["simulate", str(optimized), str(folder / "effects.yaml"), "-o", str(folder / "runs")])
    assert out.exit_code == 0, out.output
    return sorted((folder / "runs").glob("*.csv"))


@pytest.mark.end_to_end
def test_twin_recordings_of_three_trajectories_give_the_spread_between_three(optimized, tmp_path):
    first, second = (_simulated(optimized, tmp_path / name, seed) for name, seed in (("a", 1), ("b", 2)))
    config = yaml.safe_load((CONFIGS / "panda_identify_simulated.yaml").read_text())
    runs = [{"file": str(f), "role": "blocks", "trajectory": f.stem} for f in first + second]
    assert all(RunConfig.model_validate(r).trajectory for r in runs)
    config["data"]["runs"] = runs
    config["identification"]["candidates"] = ["coulomb", "viscous"]  # the spring is model error
    (tmp_path / "identify.yaml").write_text(yaml.safe_dump(config))
    out = runner.invoke(app, ["identify", str(tmp_path / "identify.yaml"), "-o", str(tmp_path / "r.h5")])
    assert out.exit_code == 0, out.output
    text = " ".join(out.output.split())
    assert "std, trajectories" in text and "the spread between the 3 distinct trajectories fitted" in text
    with h5py.File(tmp_path / "r.h5") as f:
        g = f["identification"]
        between, noise = g["base_parameters_std_between_trajectories"][()], g["base_parameters_std"][()]
        effects = g["effects"][()]
    assert between.shape == noise.shape and np.all(np.isfinite(between)) and np.all(between > 0)
    assert np.isfinite(effects["std_between_trajectories"]).sum() >= 7  # friction; a run's offset has none
    for r in runs:  # unnamed: the twins are found by their motion (measured.twins), 3 trajectories again
        del r["trajectory"]
    (tmp_path / "found.yaml").write_text(yaml.safe_dump(config))
    out = runner.invoke(app, ["identify", str(tmp_path / "found.yaml"), "-o", str(tmp_path / "found.h5")])
    text = " ".join(out.output.split())
    assert out.exit_code == 0 and "between the 3 distinct trajectories" in text
    assert text.count("repeats the motion of") == 3
    for k, r in enumerate(runs):  # each recording named apart: its own trajectory, 6 of them
        r["trajectory"] = f"t{k}"
    (tmp_path / "apart.yaml").write_text(yaml.safe_dump(config))
    out = runner.invoke(app, ["identify", str(tmp_path / "apart.yaml"), "-o", str(tmp_path / "apart.h5")])
    assert out.exit_code == 0 and "between the 6 distinct trajectories" in " ".join(out.output.split())
