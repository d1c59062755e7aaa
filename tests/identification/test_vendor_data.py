"""Data and URDFs as vendors ship them: a URDF whose moving link has an inertia no body can have is
a reference for identify (a warning naming the link) and refused by optimize; a torque channel that
carries no signal is reported and left out of the fit, the selection score and the means."""

import h5py
import numpy as np
import pytest
import yaml
from conftest import CONFIGS, assert_refused, pendulum_config, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.fitting.bodies import pseudo_inertia
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.reporting.report_file import write_identification
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.workflows.simulate import simulate_runs

runner = CliRunner()


def test_a_vendor_urdf_with_an_impossible_moving_inertia_identifies_with_a_warning_and_optimize_refuses(tmp_path):
    config = pendulum_config(tmp_path, iterations=2)
    assert runner.invoke(app, ["optimize", str(config)]).exit_code == 0
    simulate_runs(
        tmp_path / "out.h5",
        SimulationConfig(sample_rate=200, periods=3, effects={"coulomb": {"*": 0.3}}),
        tmp_path / "runs",
    )
    pendulum_config(tmp_path, tip_ixx="1.0")  # the tip, moved by the hinge, breaks the triangle inequality
    identify = {
        "robot": {"urdf": "pendulum.urdf", "active_joints": ["hinge"]},
        "data": {
            "runs": [{"file": "runs/run_1.csv", "role": "fit"}, {"file": "runs/run_2.csv", "role": "validation"}],
            "columns": {"q": ["q_hinge"], "tau": ["tau_hinge"]},
        },
        "output": str(tmp_path / "id.h5"),
    }
    problem = load_problem(write_config(tmp_path, identify, "id.yaml"), IdentifyProblem)
    report, *_ = run_identification(problem, consistent_beside=True)
    assert any("link 'tip'" in w and "no body can have" in w for w in report.warnings)
    standard = report.fit_choice.consistent.standard  # from the URDF's nearest physical inertias
    assert all(np.linalg.eigvalsh(pseudo_inertia(body))[0] > 0 for body in standard.reshape(-1, 10))
    assert report.relative_after.mean() < 0.5 * report.relative_before.mean()  # the Coulomb friction is found
    assert_refused(
        tmp_path / "runs", ["optimize", str(tmp_path / "pendulum.yaml"), "-o", str(tmp_path / "o.h5")], "link 'tip'"
    )


@pytest.mark.parametrize("dead", ["zeros", "drift"])
def test_a_torque_channel_without_signal_is_reported_left_out_and_every_mean_finite(tmp_path, dead):
    """Joint 4's channel not recorded (exact zeros) or a sensor drifting between −0.0004 and −0.007 Nm
    where the model predicts ~10 Nm: named, left out of the fit and the score, and the other joints
    identify as with the sensor (the shipped runs: ~0.6 %; with the dead rows fitted: 10 %)."""
    config = yaml.safe_load((CONFIGS / "panda_identify_simulated.yaml").read_text())
    for k, run in enumerate(config["data"]["runs"], start=1):
        table = np.genfromtxt((CONFIGS / run["file"]).resolve(), delimiter=",", names=True)
        ramp = 0.5 + 0.5 * np.sin(np.linspace(0.0, 3.0, table.size))
        table["tau_panda_joint4"] = 0.0 if dead == "zeros" else -0.0004 - 0.0066 * ramp
        np.savetxt(
            tmp_path / f"run_{k}.csv",
            table.view((float, len(table.dtype.names))),
            delimiter=",",
            header=",".join(table.dtype.names),
            comments="",
            fmt="%.10g",
        )
        run["file"] = str(tmp_path / f"run_{k}.csv")
    config["output"] = str(tmp_path / "id.h5")
    config["identification"].update(candidates=["coulomb", "viscous"], fit="least_squares")  # the effects simulated
    problem = load_problem(write_config(tmp_path, config, "id.yaml"), IdentifyProblem)
    report, robot, base, parts = run_identification(problem)
    assert any(w.startswith("panda_joint4: the torque channel carries no signal") for w in report.warnings)
    assert list(report.live) == [True, True, True, False, True, True, True]
    scored = report.selection.cross_validation.scored
    assert not scored[3] and np.delete(scored, 3).all()
    assert report.selection.weights[3] == 0.0  # its rows are not fitted
    assert np.isclose(report.selection.cv_error, np.delete(report.selection.cv_joint, 3).mean())
    assert report.mean(report.relative_after) < 1.5  # the other joints as with the sensor
    assert not report.worse_than_rigid_body[3]
    write_identification(tmp_path / "id.h5", report, robot, base, problem, parts)
    with h5py.File(tmp_path / "id.h5") as f:
        g = f["identification"]
        assert [s.decode() for s in g["dead_channels"][()]] == ["panda_joint4"]
        for name in ("relative_before", "relative_after", "relative_least_squares"):
            assert np.all(np.isfinite(g[name][()])), name
        assert np.all(np.isfinite(g["validation_runs"]["relative_after"]))
        assert np.all(np.isfinite(g["ladder"]["validation_error"]))
