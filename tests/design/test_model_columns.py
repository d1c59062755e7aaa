"""The model a design is for: no effect columns without effects, and a measured prior's joints
checked against the problem's."""

import h5py
import numpy as np
import pytest
from conftest import CONFIGS

from excite_cli.config_file import load_problem
from excite_cli.design.information import predicted_std
from excite_cli.design.model_columns import design_effects, measured_prior
from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.robot import load_robot
from excite_cli.errors import ExciteError
from excite_cli.h5 import read_strings, write_strings
from excite_cli.stored.inputs import read_inputs


def _report(source, path, joints, sigma):
    """A copy of the identify report ``source`` with other joint names (its effects' and rotors' joints
    renamed alike, in order) and validation errors."""
    path.write_bytes(source.read_bytes())
    with h5py.File(path, "a") as f:
        f["regressor"].attrs["sample_rate_Hz"] = 200.0
        g = f["identification"]
        renamed = dict(zip(read_strings(g, "joint_names"), joints))
        rows = g["effects"][()]
        rows["joint"] = [renamed[j.decode()] for j in rows["joint"]]
        rotors = [renamed[j] for j in read_strings(g, "rotor_joints")]
        del g["joint_names"], g["rms_after"], g["effects"], g["rotor_joints"]
        write_strings(g, "joint_names", joints)
        write_strings(g, "rotor_joints", rotors)
        g["rms_after"], g["effects"] = sigma, rows
    return path


def test_a_rigid_design_has_no_effect_columns_and_a_result_prior_no_weights(optimized):
    problem = load_problem(CONFIGS / "smoke.yaml")
    robot = load_robot(problem.robot, problem.folder)
    assert (
        design_effects(
            problem.effects,
            read_inputs(problem.effects.model, problem.sequence.prior, problem.folder),
            robot,
            compute_base_parameters(robot),
        )
        is None
    )
    problem.sequence.prior = str(optimized)  # an optimize result: its rows are the design's own
    assert (
        measured_prior(read_inputs(problem.effects.model, problem.sequence.prior, problem.folder).prior, robot) is None
    )


def test_a_report_of_the_problems_joints_weighs_them_and_of_others_is_refused(report_file, tmp_path):
    problem = load_problem(CONFIGS / "smoke.yaml")
    robot = load_robot(problem.robot, problem.folder)
    sigma = np.linspace(0.1, 0.7, robot.n_joints)
    problem.sequence.prior = str(_report(report_file, tmp_path / "ok.h5", robot.joint_names[::-1], sigma))
    measured = measured_prior(read_inputs(problem.effects.model, problem.sequence.prior, problem.folder).prior, robot)
    assert measured.rate == 200.0 and measured.joints == robot.joint_names[::-1]
    others = [f"joint_{k}" for k in range(robot.n_joints)]
    problem.sequence.prior = str(_report(report_file, tmp_path / "other.h5", others, np.ones(robot.n_joints)))
    with pytest.raises(ExciteError, match=r"sequence\.prior.*identified the joints joint_0"):
        measured_prior(read_inputs(problem.effects.model, problem.sequence.prior, problem.folder).prior, robot)


def test_predicted_standard_deviations_match_least_squares_on_noisy_data():
    """√diag((CᵀC)⁻¹)·σ against the spread of 2000 least-squares fits of noisy torques; a column the
    rows do not determine (a copy of another) is inf."""
    rng = np.random.default_rng(0)
    C = rng.standard_normal((60, 3)) * [1.0, 0.2, 5.0]
    estimates = [
        np.linalg.lstsq(C, C @ [1.0, 2.0, 3.0] + 0.3 * rng.standard_normal(60), rcond=None)[0] for _ in range(2000)
    ]
    np.testing.assert_allclose(predicted_std(C, 0.3), np.std(estimates, axis=0), rtol=0.06)
    assert np.isinf(predicted_std(np.hstack([C, C[:, :1]]), 0.3)).tolist() == [True, False, False, True]
