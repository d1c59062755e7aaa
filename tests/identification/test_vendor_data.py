"""Data and URDFs as vendors ship them: a URDF whose moving link has an inertia no body can have is
a reference for identify (a warning naming the link) and refused by optimize; a torque channel that
carries no signal is reported and left out of the selection score."""

import numpy as np
import yaml
from conftest import CONFIGS, assert_refused, pendulum_config, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.fitting.physical import pseudo_inertia
from excite_cli.identification.pipeline import run_identification
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


def test_a_torque_channel_without_signal_is_reported_and_not_scored(tmp_path):
    config = yaml.safe_load((CONFIGS / "panda_identify_simulated.yaml").read_text())
    for k, run in enumerate(config["data"]["runs"], start=1):
        table = np.genfromtxt((CONFIGS / run["file"]).resolve(), delimiter=",", names=True)
        table["tau_panda_joint7"] = 0.0  # the channel was not recorded
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
    report, *_ = run_identification(load_problem(write_config(tmp_path, config, "id.yaml"), IdentifyProblem))
    assert any(w.startswith("panda_joint7: the torque channel carries no signal") for w in report.warnings)
    scored = report.selection.cross_validation.scored
    assert not scored[6] and scored[:6].all()
    assert report.selection.cv_error == report.selection.cross_validation.error(report.selection.terms)[0]
    assert np.isclose(report.selection.cv_error, report.selection.cv_joint[:6].mean())
