"""Same seed, same arrays; a run killed with SIGKILL keeps a valid file with its finished iterations,
and `--resume` ends with the table of an uninterrupted run; results are not replaced by accident."""

import copy
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest
import yaml
from conftest import UR5, write_config
from typer.testing import CliRunner

from excite_cli.cli import app

runner = CliRunner()


def _config(tmp_path, iterations=3):
    data = copy.deepcopy(UR5)
    data["trajectory"].update(harmonics=3, cost_samples=20, cost_period=0.4, constraint_period=0.05)
    data["optimizer"] = {"max_iterations": 40, "restarts": 2, "seed": 4, "workers": 1}
    data["sequence"] = {"iterations": iterations}
    return write_config(tmp_path, data)


def _arrays(path):
    with h5py.File(path) as f:
        arrays = {
            f"{k}/{name}": f["iterations"][k][name][()] for k in f["iterations"] for name in ("alpha", "regressor", "q")
        }
        table = f["table"][()]
        arrays.update({f"table/{name}": table[name] for name in table.dtype.names})  # NaN equals NaN per column
        return arrays


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("whole")
    out = tmp / "whole.h5"
    run = runner.invoke(app, ["optimize", str(_config(tmp)), "-o", str(out)])
    assert run.exit_code == 0, run.output
    return out


def test_same_seed_gives_bit_identical_arrays(uninterrupted, tmp_path):
    again = tmp_path / "again.h5"
    assert runner.invoke(app, ["optimize", str(_config(tmp_path)), "-o", str(again)]).exit_code == 0
    first, second = _arrays(uninterrupted), _arrays(again)
    assert first.keys() == second.keys() and len(first) == 3 * 3 + 8  # 3 iterations × 3 arrays, 8 table columns
    for key in first:
        np.testing.assert_array_equal(first[key], second[key], err_msg=key)


def test_resume_after_sigkill_ends_as_an_uninterrupted_run(uninterrupted, tmp_path):
    out = tmp_path / "killed.h5"
    process = subprocess.Popen(
        [sys.executable, "-m", "excite_cli", "optimize", str(_config(tmp_path)), "-o", str(out)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 120
    while not out.exists() and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.05)
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    with h5py.File(out) as f:  # valid, with the iterations finished before the kill
        kept = len(f["iterations"])
    assert 1 <= kept < 3
    resumed = runner.invoke(app, ["optimize", str(_config(tmp_path)), "-o", str(out), "--resume"])
    assert resumed.exit_code == 0, resumed.output
    whole, done = _arrays(uninterrupted), _arrays(out)
    for name in ("table/cond_own", "table/cond_stacked"):
        np.testing.assert_array_equal(done[name], whole[name])
    for key in whole:
        np.testing.assert_array_equal(done[key], whole[key], err_msg=key)


def test_resume_refuses_a_result_of_another_config(uninterrupted, tmp_path):
    path = _config(tmp_path)
    data = yaml.safe_load(path.read_text())
    data["optimizer"]["seed"] = 5
    path.write_text(yaml.safe_dump(data))
    run = runner.invoke(app, ["optimize", str(path), "-o", str(uninterrupted), "--resume"])
    assert run.exit_code == 2 and "was made with another config (optimizer differ)" in run.output


def test_existing_result_is_kept_without_force(uninterrupted, tmp_path):
    before = uninterrupted.read_bytes()
    run = runner.invoke(app, ["optimize", str(_config(tmp_path, iterations=1)), "-o", str(uninterrupted)])
    assert run.exit_code == 2 and "exists; use --force" in run.output
    assert uninterrupted.read_bytes() == before


def test_effective_config_is_stored(uninterrupted, tmp_path):
    with h5py.File(uninterrupted) as f:
        effective, original = yaml.safe_load(f.attrs["config"]), yaml.safe_load(f.attrs["config_original"])
    assert (
        effective["sequence"]["iterations"] == 3 and effective["optimizer"]["tolerance"] == 1e-6
    )  # defaults filled in
    assert "tolerance" not in original["optimizer"]
    out = tmp_path / "k1.h5"
    assert (
        runner.invoke(app, ["optimize", str(_config(tmp_path)), "-o", str(out), "-k", "1", "--seed", "7"]).exit_code
        == 0
    )
    with h5py.File(out) as f:
        effective = yaml.safe_load(f.attrs["config"])
    assert effective["sequence"]["iterations"] == 1 and effective["optimizer"]["seed"] == 7  # the overrides that ran


def test_each_iteration_is_a_new_motion_and_the_file_says_how_new(uninterrupted):
    """The stored correlation of each iteration with the earlier ones is that of the stored joint
    positions (numpy's corrcoef of the mean-removed samples, computed here), and no iteration repeats
    an earlier one (correlation below 0.9)."""
    with h5py.File(uninterrupted) as f:
        q = {int(k): f["iterations"][k]["q"][()] for k in f["iterations"]}
        stored = {int(k): f["iterations"][k]["correlations"][()] for k in f["iterations"]}
        table = f["table"][()]
    for k in sorted(q):
        expected = [
            np.corrcoef((q[k] - q[k].mean(0)).ravel(), (q[j] - q[j].mean(0)).ravel())[0, 1] for j in range(1, k)
        ]
        np.testing.assert_allclose(stored[k], expected, rtol=1e-10, atol=1e-12)
    assert np.isnan(table["max_correlation"][0]) and np.all(table["max_correlation"][1:] < 0.9)
