"""Arms as industry builds them (issue 32): a UR5 whose motor 6 turns with q5 + q6 (a coupled wrist),
simulated with every motor's rotor inertia and friction acting through the transmission, recorded on
the motor side or converted to the joint side; runs from several files or without a time column."""

import numpy as np
import pytest
from conftest import UR5, assert_refused, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.dynamics.robot import load_robot
from excite_cli.errors import ExciteError
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.least_squares import joint_weights, least_squares, predict, torque_errors
from excite_cli.identification.fitting.normal import NormalEquations
from excite_cli.identification.measured.measurements import Run, check_against_limits
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.prepared import prepare_data
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.workflows.simulate import simulate_runs

runner = CliRunner()
JOINTS = UR5["robot"]["active_joints"]
N = 101.0  # gear ratio of every motor
COUPLING = np.eye(6)
COUPLING[5, 4] = 1.0  # motor 6 turns with q5 + q6
TRUTH = {"armature": 2e-5, "coulomb": 0.01, "viscous": 2e-5}  # every motor's own [kg·m², Nm, Nm·s/rad]
MOTOR = {"armature": "Ia", "coulomb": "Fc", "viscous": "Fv"}  # the coefficients of a coupled motor's effect


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    folder = tmp_path_factory.mktemp("wrist")
    data = {**UR5, "limits": {**UR5["limits"], "velocity": 2.0}}
    data["optimizer"] = {"max_iterations": 60, "restarts": 3, "workers": 1}
    data["sequence"] = {"iterations": 3}
    assert (
        runner.invoke(app, ["optimize", str(write_config(folder, data)), "-o", str(folder / "ur5.h5")]).exit_code == 0
    )
    for side, noise in (("motor", 0.002), ("joint", 0.2)):  # the same 0.2 Nm on the joints
        sim = SimulationConfig(
            sample_rate=500,
            periods=4,
            torque_noise=noise,
            seed=3,
            motor_effects={e: {"*": v} for e, v in TRUTH.items()},
            transmission={"gear_ratios": [N] * 6, "coupling": COUPLING.tolist()},
            motor_side=side == "motor",
        )
        simulate_runs(folder / "ur5.h5", sim, folder / side)
    return folder


def _config(folder, side, **data):
    return {
        "robot": UR5["robot"],
        "data": {
            "runs": [
                {"file": f"{side}/run_{k}.csv", "role": role} for k, role in ((1, "fit"), (2, "fit"), (3, "validation"))
            ],
            "columns": {"q": [f"q_{j}" for j in JOINTS], "tau": [f"tau_{j}" for j in JOINTS]},
            **data,
        },
        "identification": {"fit": "least_squares"},
        "output": str(folder / f"{side}.h5"),
    }


def _problem(folder, name, config):
    return load_problem(write_config(folder, config, name), IdentifyProblem)


def _true_error(problem, terms):
    """Mean relative validation error [%] of the true model (``terms``) fitted on the fit data."""
    robot = load_robot(problem.robot, problem.folder, joint_rows_only=True)
    data = prepare_data(problem, robot, compute_base_parameters(robot), terms)
    normal = NormalEquations(data.fit, terms)
    fit = least_squares(normal, terms, joint_weights(normal, True))
    measured = data.validation.tau.reshape(-1, 6)
    return torque_errors(measured, predict(data.validation, fit.x, terms))[2].mean()


def _true_terms(motor_coordinate):
    own = [Term(e, j) for e in TRUTH for j in range(5)]  # motors 1-5 drive their joints alone
    return own + [Term("motor", 4, None, motor_coordinate)]


def test_motor_side_data_with_the_transmission_gives_the_coupled_motor_s_own_values(recordings):
    transmission = {"gear_ratios": [N] * 6, "coupling": COUPLING.tolist()}
    problem = _problem(
        recordings, "motor.yaml", _config(recordings, "motor", transmission=transmission, motor_side=True)
    )
    report, *_ = run_identification(problem)
    coupled = {c: v for t, c, v, _ in report.effect_values() if t.coupling is not None}
    assert set(coupled) == set(MOTOR.values())  # the motor as one group: inertia, Coulomb and viscous
    for effect, value in TRUTH.items():
        assert coupled[MOTOR[effect]] == pytest.approx(value, rel=0.05)  # motor 6's own inertia and friction
    motor = tuple(N * COUPLING[5])
    assert report.relative_after.mean() <= _true_error(problem, _true_terms(motor)) + 0.5


def test_joint_side_data_with_nothing_declared_finds_the_coupled_wrist(recordings):
    problem = _problem(recordings, "joint.yaml", _config(recordings, "joint"))
    report, *_ = run_identification(problem)
    coupled = [t.label(JOINTS) for t in report.selection.terms if t.coupling is not None]
    assert coupled == ["motor of wrist_2_joint + wrist_3_joint"]  # inertia, Coulomb and viscous together
    assert report.relative_after.mean() <= _true_error(problem, _true_terms((0, 0, 0, 0, 1.0, 1.0))) + 1.0


def test_motor_angles_given_as_joint_angles_are_refused_in_one_line(recordings, tmp_path):
    config = write_config(recordings, _config(recordings, "motor"), "wrong.yaml")
    assert_refused(tmp_path, ["identify", str(config), "-o", str(tmp_path / "r.h5")], "motor angles?")


def test_motor_velocities_given_as_joint_velocities_are_refused_naming_the_column():
    t = np.linspace(0.0, 1.0, 11)
    q, qd = np.zeros((11, 2)), np.zeros((11, 2))
    qd[:, 1] = N * 0.5  # 0.5 rad/s at the joint, recorded at the motor
    run = Run("r.csv", "fit", t, q, qd, None, q, 0)
    lower, upper = np.full(2, -3.0), np.full(2, 3.0)
    assert check_against_limits(run, ["a", "b"], lower, upper, np.array([2.0, 0.0])) is run  # no limit: kept
    with pytest.raises(ExciteError) as refused:
        check_against_limits(run, ["a", "b"], lower, upper, np.array([2.0, 3.0]))
    assert refused.value.field == "data.columns.qd" and "b reaches 50.5 rad/s" in str(refused.value)
    qd[:, 1] = 8.9  # below 3 × the limit: a fast joint, not a motor
    assert check_against_limits(run, ["a", "b"], lower, upper, np.array([2.0, 3.0])) is run


def test_runs_from_separate_files_a_file_without_time_and_unit_factors_give_the_data_of_one_file(recordings):
    q_names, tau_names = [f"q_{j}" for j in JOINTS], [f"tau_{j}" for j in JOINTS]
    for k in (1, 2, 3):
        table = np.genfromtxt(recordings / f"joint/run_{k}.csv", delimiter=",", names=True)
        (recordings / f"joint/split_{k}").mkdir()
        for name, columns, scale in (
            ("position", ["time"] + q_names, 1.0),
            ("effort", ["time"] + tau_names, 1.0),
            ("log", q_names + tau_names, 1000.0),  # torques logged in mNm
        ):
            values = np.column_stack([table[c] for c in columns])
            values[:, -len(tau_names) :] *= scale
            np.savetxt(
                recordings / f"joint/split_{k}/{name}.csv",
                values,
                delimiter=",",
                header=",".join(columns),
                comments="",
                fmt="%.12g",
            )
    split = _config(recordings, "joint")
    for r in split["data"]["runs"]:
        folder = r["file"].replace("run_", "split_").removesuffix(".csv")
        r["file"] = [f"{folder}/position.csv", f"{folder}/effort.csv"]  # joined on their time columns
    split["data"]["columns"] = {"q": [f"position/{c}" for c in q_names], "tau": [f"effort/{c}" for c in tau_names]}
    timeless = _config(recordings, "joint", sample_rate=500.0)  # a log at a known rate, no time column
    for r in timeless["data"]["runs"]:
        r["file"] = r["file"].replace("run_", "split_").replace(".csv", "/log.csv")
    factors = {c: 1e-3 for c in tau_names}  # mNm → Nm
    timeless["data"]["columns"] = {"time": None, "q": q_names, "tau": tau_names, "factors": factors}
    terms = _true_terms((0, 0, 0, 0, 1.0, 1.0))

    def data_of(name, config):
        problem = _problem(recordings, name, config)
        robot = load_robot(problem.robot, problem.folder, joint_rows_only=True)
        return prepare_data(problem, robot, compute_base_parameters(robot), terms)

    reference = data_of("joint.yaml", _config(recordings, "joint"))
    for name, config in (("split.yaml", split), ("timeless.yaml", timeless)):
        data = data_of(name, config)
        for side in ("fit", "validation"):
            ours, theirs = getattr(data, side), getattr(reference, side)
            np.testing.assert_allclose(ours.tau, theirs.tau, rtol=1e-7, atol=1e-9)
            np.testing.assert_allclose(ours.regressor, theirs.regressor, rtol=1e-7, atol=1e-9)
            for t in terms:
                np.testing.assert_allclose(ours.blocks[t], theirs.blocks[t], rtol=1e-7, atol=1e-9)


def test_a_joint_whose_urdf_gives_no_range_is_not_judged_by_it():
    """A revolute joint without lower/upper in the URDF is read as [0, 0]: ±1.7 rad on it is data, not
    motor angles; the joint beside it, with a range, is still judged."""
    t = np.linspace(0.0, 1.0, 11)
    q = np.column_stack([1.7 * np.sin(6.0 * t), np.zeros(11)])
    run = Run("r.csv", "fit", t, q, None, None, q, 0)
    velocity = np.zeros(2)
    assert check_against_limits(run, ["a", "b"], np.zeros(2), np.zeros(2), velocity) is run
    q[:, 1] = 40.0  # motor angles on b, whose range is [-3, 3] rad
    with pytest.raises(ExciteError) as refused:
        check_against_limits(run, ["a", "b"], np.array([0.0, -3.0]), np.array([0.0, 3.0]), velocity)
    assert "b reaches 40 rad" in str(refused.value)
