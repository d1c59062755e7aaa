"""One library function per command, called as the command line calls them, on the smoke problem:
optimize, export, view, simulate, identify, validate, verify-gradient and compare-random, each
checked against what it wrote and against independent truth."""

import h5py
import numpy as np
import pinocchio as pin
import pytest
from conftest import CONFIGS, JOINTS, robot_of, write_config

from excite_cli import workflows
from excite_cli.config_file import load_problem
from excite_cli.errors import ExciteError
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.workflows.compare import run_compare_random
from excite_cli.workflows.export import run_export
from excite_cli.workflows.identify import run_identify
from excite_cli.workflows.optimize import run_optimize
from excite_cli.workflows.simulate import simulate_runs
from excite_cli.workflows.validate import run_validate
from excite_cli.workflows.verify_gradient import run_verify
from excite_cli.workflows.view import run_view


@pytest.fixture(scope="module")
def smoke(tmp_path_factory):
    folder = tmp_path_factory.mktemp("workflows")
    problem = load_problem(CONFIGS / "smoke.yaml")
    problem.optimizer.max_iterations = 20
    run = run_optimize(problem, folder / "smoke.h5")
    return folder, problem, run


def test_optimize_writes_its_iterations_and_plots(smoke):
    _, problem, run = smoke
    assert len(run.results) == problem.sequence.iterations and all(p.exists() for p in run.plots)
    with h5py.File(run.target) as f:
        np.testing.assert_array_equal(f["iterations/2/alpha"][()], run.results[1].alpha)
        assert f["table"]["cond_stacked"][-1] == run.results[-1].cond_stacked


def test_export_plays_the_last_iteration_at_the_rate_from_home_to_home(smoke):
    folder, problem, run = smoke
    played, path = run_export(run.target, rate=200.0, output=folder / "played.csv")
    np.testing.assert_allclose(np.diff(played.time), 1 / 200.0)
    np.testing.assert_allclose(played.q[[0, -1]], np.tile(run.excitation.home, (2, 1)), atol=1e-12)
    assert path.exists() and played.iteration == len(run.results) and played.max_violation <= 0


@pytest.mark.parametrize("writer", ["export", "simulate"])
def test_a_bag_writer_with_force_leaves_a_user_s_folder_whole(smoke, writer):
    """`export --format rosbag2 --force` and `simulate --force` with `recording: rosbag2` over a folder
    that holds a dataset's own metadata.yaml and notes: refused in one line, every file kept."""
    folder, _, run = smoke
    site = folder / f"site_{writer}"
    target = site / "run_1" if writer == "simulate" else site
    target.mkdir(parents=True)
    (target / "metadata.yaml").write_text("title: my data\nauthor: me\n")
    (target / "notes.txt").write_text("mine")
    with pytest.raises(ExciteError, match="not only a ROS 2 bag"):
        if writer == "export":
            run_export(run.target, rate=200.0, fmt="rosbag2", output=site, force=True)
        else:
            sim = SimulationConfig(sample_rate=100, periods=1, recording="rosbag2", effects={"coulomb": {"*": 0.5}})
            simulate_runs(run.target, sim, site, force=True)
    assert sorted(p.name for p in target.iterdir()) == ["metadata.yaml", "notes.txt"]
    assert (target / "notes.txt").read_text() == "mine"


def test_view_writes_one_scene(smoke):
    folder, _, run = smoke
    path = run_view(run.target, output=folder / "scene.html", rate=5.0)
    assert path.stat().st_size > 100_000 and b"<html" in path.read_bytes()[:1000].lower()


def test_simulated_runs_are_the_urdf_torques_plus_the_effects(smoke):
    folder, _, run = smoke
    sim = SimulationConfig(sample_rate=100, periods=1, effects={"coulomb": {"*": 0.5}})
    paths = simulate_runs(run.target, sim, folder / "sim", force=True)
    assert len(paths) == len(run.results)
    table = np.genfromtxt(paths[0], delimiter=",", names=True)
    robot = robot_of(load_problem(CONFIGS / "smoke.yaml"))
    q = np.column_stack([table[f"q_{j}"] for j in JOINTS])
    qd, qdd = run.excitation.trajectory.basis(table["time"]).evaluate(run.results[0].alpha)[1:]
    data = robot.model.createData()
    for k in range(0, len(q), 37):
        expected = pin.rnea(robot.model, data, *robot.state(q[k], qd[k], qdd[k])) + 0.5 * np.tanh(qd[k] / 0.01)
        np.testing.assert_allclose([table[f"tau_{j}"][k] for j in JOINTS], expected[robot.v_idx], atol=1e-6)


def test_identify_and_validate_find_the_simulated_friction(smoke):
    folder, _, run = smoke
    sim = SimulationConfig(sample_rate=200, periods=4, torque_noise=0.01, effects={"coulomb": {"*": 0.5}})
    simulate_runs(run.target, sim, folder / "id", force=True)
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {
            "runs": [{"file": "run_1.csv", "role": "fit"}, {"file": "run_2.csv", "role": "validation"}],
            "columns": {"q": [f"q_{j}" for j in JOINTS], "tau": [f"tau_{j}" for j in JOINTS]},
        },
        "identification": {"candidates": ["coulomb", "viscous"], "fit": "least_squares"},
    }
    path = write_config(folder / "id", config, "identify.yaml")
    identified = run_identify(load_problem(path, IdentifyProblem), folder / "id" / "report.h5")
    found = {(t.effect, t.joint) for t in identified.report.selection.terms}
    assert found == {("coulomb", j) for j in range(7)}
    _, errors = run_validate(identified.target, path)
    np.testing.assert_allclose(errors[1].relative, identified.report.relative_after, rtol=1e-9)  # the same run


def test_verify_gradient_passes_on_the_smoke_problem(smoke):
    _, problem, _ = smoke
    verification = run_verify(problem, None, ["log_cond"], 1e-6, 0, 1e-6)
    assert verification.worst <= 1e-6 and [name for _, name, _ in verification.gradients] == ["log_cond"]


def test_compare_random_beside_the_optimized_result(smoke):
    folder, problem, run = smoke
    problem = problem.model_copy(deep=True)
    problem.random_baseline.pool_size = 12
    comparison = run_compare_random(problem, run.target, folder / "random.h5")
    assert len(comparison.random_table) == len(run.results) and comparison.pool == 12
    np.testing.assert_array_equal(comparison.optimized_table["cond_stacked"], [r.cond_stacked for r in run.results])
    assert comparison.random_table["cond_stacked"][-1] > comparison.optimized_table["cond_stacked"][-1]


def test_the_command_line_sees_every_workflow():
    # the command line calls these alone (tests/test_house.py: nothing else of the library)
    assert {
        "run_optimize",
        "run_export",
        "run_view",
        "run_identify",
        "run_validate",
        "run_verify",
        "run_compare_random",
        "simulate_runs",
    } <= set(workflows.__all__)
