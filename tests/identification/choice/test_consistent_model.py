"""Every joint's rotor is a body of the consistent fit, whether or not the effect search added it."""

import numpy as np
from conftest import panda_runs_config, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.identification.choice.consistent_model import consistent_model
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term
from excite_cli.identification.pipeline import run_identification

runner = CliRunner()


def test_a_rotor_the_search_cannot_add_is_held_apart_and_the_links_keep_their_masses(tmp_path, optimized):
    """A simulated Panda with 0.2 kg·m² of armature on joint 4 (its column is not among the base
    parameters', but the search may only add friction): the consistent fit holds it as a rotor with a
    column of its own within 5 %, the other joints' near none, every link's mass within 1 % of the
    URDF (the truth), and predicts the held-out blocks better than least squares of the same model."""
    sim = {
        "sample_rate": 250,
        "periods": 2,
        "torque_noise": 0.05,
        "seed": 5,
        "effects": {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}, "armature": {"panda_joint4": 0.2}},
    }
    result = runner.invoke(
        app, ["simulate", str(optimized), str(write_config(tmp_path, sim, "effects.yaml")), "-o", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    config = panda_runs_config([f"run_{k}.csv" for k in (1, 2, 3)], fit="consistent", candidates=["coulomb", "viscous"])
    problem = load_problem(write_config(tmp_path, config, "identify.yaml"), IdentifyProblem)
    report, robot, _, _ = run_identification(problem)
    fit = report.consistent
    assert all(t.effect in ("coulomb", "viscous") for t in report.selection.terms)
    rotors = dict(zip(fit.rotor_joints, zip(fit.rotors, fit.own_columns)))
    assert rotors["panda_joint4"][1] and not rotors["panda_joint1"][1]  # a column of its own; joint 1's regroups
    np.testing.assert_allclose(rotors["panda_joint4"][0], 0.2, rtol=0.05)
    assert all(a <= 2e-3 for j, (a, _) in rotors.items() if j != "panda_joint4")
    assert "rotor of panda_joint4 ≥ 0" not in fit.active and not any(a.startswith("Ia ") for a in fit.active)
    np.testing.assert_allclose(fit.standard[0::10], robot.urdf_parameters()[0::10], rtol=0.01)
    assert report.mean(report.relative_consistent) < 0.8 * report.mean(report.relative_least_squares)
    # what it predicts with: the model's terms, then its rotor columns, the coefficients in their order
    terms, x = consistent_model(fit, report.selection.terms, robot.joint_names)
    assert terms[len(report.selection.terms) :] == [Term("armature", j) for j in range(2, 7)]
    assert x.size == fit.base.size + fit.effects.size + 5 and x[fit.base.size + fit.effects.size + 1] == fit.rotors[3]
