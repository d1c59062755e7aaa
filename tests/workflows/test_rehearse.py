"""``excite rehearse``: the export played in MuJoCo (its own compilation of the robot, integrator and
contacts, which nobody here wrote) on the lab's controller. MuJoCo's inverse dynamics of the same inertias
applies the export's feed-forward torque and tracks it; a torque over its limit, a contact with a shape
of the world and a standing robot's balance are reported and refused; the recording is the run as played."""

import shutil

import h5py
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import CONFIGS, panda_mjcf, panda_runs_config, small, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.robot_files import example_robot_data_root
from excite_cli.errors import ExciteError
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.workflows.export import played_result
from excite_cli.workflows.optimize import run_optimize
from excite_cli.workflows.rehearse import run_rehearse


def rms(a: np.ndarray) -> float:
    return float(np.sqrt(np.mean(a**2)))


@pytest.fixture(scope="module")
def optimized(tmp_path_factory):
    """The smoke problem's first iteration (the Panda, 3 harmonics)."""
    folder = tmp_path_factory.mktemp("smoke")
    problem = load_problem(CONFIGS / "smoke.yaml")
    problem.sequence.iterations, problem.rehearsal.joint_losses = 1, None  # MuJoCo's joints as the URDF's
    run_optimize(problem, folder / "smoke.h5", force=True)
    return folder / "smoke.h5"


@pytest.fixture(scope="module")
def panda(optimized, tmp_path_factory):
    folder = tmp_path_factory.mktemp("rehearsal")
    return run_rehearse(optimized, 1, record=folder / "runs", plot=folder / "r.png"), folder


def test_mujoco_applies_the_exported_feed_forward_and_tracks_it(panda):
    done, folder = panda
    [it] = done.iterations
    assert not done.failed and not it.played.contacts and it.played.drop is None
    # MuJoCo's dynamics of the URDF's inertias needs the torque pinocchio's RNEA exported: the PD adds ~1 %
    assert rms(it.played.tau - it.export.tau) < 0.02 * rms(it.export.tau)
    assert np.abs(it.played.q - it.export.q).max() < np.radians(0.1)
    assert (folder / "r.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_recording_is_the_run_as_played_in_columns_identify_reads(panda):
    done, folder = panda
    [it], [path] = done.iterations, done.recordings
    assert path == folder / "runs" / "rehearsal_1.csv"
    table = np.genfromtxt(path, delimiter=",", names=True, comments="#")
    names = it.export.joint_names
    assert table.dtype.names == ("time", *[f"q_{j}" for j in names], *[f"tau_{j}" for j in names])
    np.testing.assert_allclose(np.column_stack([table[f"q_{j}"] for j in names]), it.played.q, atol=1e-9)
    np.testing.assert_allclose(np.column_stack([table[f"tau_{j}"] for j in names]), it.played.tau, rtol=1e-8, atol=1e-8)


def test_the_lab_mjcf_of_the_same_robot_plays_the_same(optimized, panda, tmp_path):
    done, _ = panda
    mjcf = run_rehearse(optimized, 1, mjcf=panda_mjcf(tmp_path), plot=tmp_path / "m.png")
    ours, theirs = done.iterations[0].played, mjcf.iterations[0].played
    assert not mjcf.failed
    assert rms(theirs.tau - ours.tau) < 1e-3 * rms(ours.tau)


def test_a_speed_the_export_refuses_is_played_and_named_with_the_limit(optimized, tmp_path):
    with pytest.raises(ExciteError) as refused:
        played_result(optimized, 1, speed=1.5)
    done = run_rehearse(optimized, 1, speed=1.5, plot=tmp_path / "fast.png")
    [it] = done.iterations
    assert done.failed and it.refused and it.refused in refused.value.problem
    assert not it.played.contacts and np.abs(it.played.q - it.export.q).max() < np.radians(0.5)  # played all the same


def test_the_recording_carries_the_effects_file_s_noise_and_nothing_else(optimized, panda, tmp_path):
    done, _ = panda
    noise = SimulationConfig(torque_noise=0.05, position_noise=1e-4, seed=3)
    noisy = run_rehearse(optimized, 1, record=tmp_path / "runs", plot=tmp_path / "n.png", noise=noise)
    table = np.genfromtxt(noisy.recordings[0], delimiter=",", names=True, comments="#")
    names = done.iterations[0].export.joint_names
    clean = done.iterations[0].played  # MuJoCo is deterministic: the same run, without noise
    q_noise = np.column_stack([table[f"q_{j}"] for j in names]) - clean.q
    tau_noise = np.column_stack([table[f"tau_{j}"] for j in names]) - clean.tau
    assert q_noise.std() == pytest.approx(1e-4, rel=0.05) and tau_noise.std() == pytest.approx(0.05, rel=0.05)
    assert abs(tau_noise.mean()) < 0.05 * 0.05
    for given, field in [(dict(effects={"viscous": {"*": 0.1}}), "effects"), (dict(sample_rate=500.0), "sample_rate")]:
        with pytest.raises(ExciteError, match=field):
            run_rehearse(optimized, 1, record=tmp_path / "x", noise=SimulationConfig(**given))
    with pytest.raises(ExciteError, match="a record folder"):
        run_rehearse(optimized, 1, noise=noise)


def test_the_command_reads_the_effects_file_and_names_what_it_lacks(optimized, tmp_path):
    (tmp_path / "noise.yaml").write_text("torque_noise: 0.1\n")
    result = CliRunner().invoke(app, ["rehearse", str(optimized), "--effects", str(tmp_path / "noise.yaml")])
    assert result.exit_code == 2 and "--effects: the noise is added to a recording" in result.output, result.output
    assert not optimized.with_name("smoke_rehearsal.png").exists()  # refused before anything is played


def changed_result(result, folder, change) -> str:
    """A copy of ``result`` whose stored config ``change`` edits."""
    copy = folder / "changed.h5"
    shutil.copy(result, copy)
    with h5py.File(copy, "r+") as f:
        config = yaml.safe_load(str(f.attrs["config"]))
        change(config)
        f.attrs["config"] = yaml.safe_dump(config)
    return str(copy)


def test_a_torque_over_its_limit_is_refused_naming_the_joint(optimized, tmp_path):
    urdf = example_robot_data_root() / "example-robot-data/robots/panda_description/urdf/panda.urdf"
    text = urdf.read_text().replace("package://", f"{example_robot_data_root()}/")
    joint2 = text.index('name="panda_joint2"')
    effort = text.index('effort="87.0"', joint2)
    (tmp_path / "panda.urdf").write_text(text[:effort] + 'effort="5"' + text[effort + len('effort="87.0"') :])

    def weaker(config):
        config["robot"].update(urdf=str(tmp_path / "panda.urdf"), source="file")

    result = CliRunner().invoke(app, ["rehearse", changed_result(optimized, tmp_path, weaker), "-k", "1"])
    assert result.exit_code == 1, result.output
    assert "over its limit: panda_joint2" in result.output and "refused: iteration 1" in result.output


def test_a_contact_in_the_lab_scene_is_refused_naming_the_bodies(optimized, panda, tmp_path):
    """A box the lab's MJCF has where the hand passes mid-motion (excite's config does not know it)."""
    done, _ = panda
    it = done.iterations[0]
    robot = build_excitation(load_problem(CONFIGS / "smoke.yaml")).robot
    data, frame = robot.model.createData(), robot.model.getFrameId("panda_link7")
    rest = 0 * it.export.q[0]
    pin.framesForwardKinematics(robot.model, data, robot.state(it.export.q[len(it.export.q) // 2], rest, rest)[0])
    where = " ".join(f"{x:.4f}" for x in data.oMf[frame].translation)
    mjcf = panda_mjcf(tmp_path)
    box = f'<geom name="box_on_the_table" type="sphere" size="0.05" pos="{where}"/>'
    mjcf.write_text(mjcf.read_text().replace("<worldbody>", f"<worldbody>{box}", 1))
    result = CliRunner().invoke(
        app, ["rehearse", str(optimized), "-k", "1", "--mjcf", str(mjcf), "--plot", str(tmp_path / "p.png")]
    )
    assert result.exit_code == 1, result.output
    assert "with world at" in result.output and "refused: iteration 1" in result.output


@pytest.fixture(scope="module")
def standing(tmp_path_factory):
    """A short optimization of the shipped G1 problem (3 harmonics, one iteration), rehearsed (35 s: its
    tests run with make end-to-end)."""
    folder = tmp_path_factory.mktemp("g1")
    problem = small(load_problem(CONFIGS / "g1_arms.yaml"), harmonics=3)
    problem.sequence.iterations, problem.optimizer.restarts, problem.optimizer.max_iterations = 1, 1, 60
    problem.optimizer.polish_rounds, problem.rehearsal.rate = 0, 500.0  # a 500 Hz controller
    run_optimize(problem, folder / "g1.h5", force=True)
    return run_rehearse(folder / "g1.h5", plot=folder / "g1.png"), folder


@pytest.mark.end_to_end
def test_a_standing_robot_stands_on_its_feed_forward_where_excite_predicts(standing):
    done, _ = standing
    [it] = done.iterations
    fed, alone = it.played, it.alone
    assert not fed.fell and fed.margin.min() > 0.01
    gap = np.sqrt(np.nanmean(np.sum((fed.cop - it.predicted) ** 2, axis=1)))
    alone_gap = np.sqrt(np.nanmean(np.sum((alone.cop - it.predicted) ** 2, axis=1)))
    assert gap < 0.01 and alone_gap > 2 * gap  # m: PD alone sways away from the rigid prediction
    assert it.export.held is not None and fed.held_tau.shape[1] == len(it.export.held.joint_names)


@pytest.mark.end_to_end
def test_a_config_gives_the_controller_without_optimizing_again(standing, tmp_path):
    done, folder = standing
    data = yaml.safe_load((CONFIGS / "g1_arms.yaml").read_text())
    data["rehearsal"].update(held_feedforward=False, rate=500.0)
    config = write_config(tmp_path, data)
    alone = run_rehearse(folder / "g1.h5", plot=tmp_path / "a.png", config=config)
    assert alone.controller.held_feedforward is False and alone.iterations[0].alone is None
    np.testing.assert_allclose(alone.iterations[0].played.cop, done.iterations[0].alone.cop, atol=1e-9)


@pytest.mark.end_to_end
def test_identify_finds_in_the_rehearsal_the_joint_losses_mujoco_played(tmp_path):
    """The smoke problem's two iterations rehearsed with MuJoCo's joints given damping 0.5 N·m·s/rad,
    armature 0.05 kg·m² and dry friction 0.3 N·m (configs/smoke.yaml), recorded, identified with nothing
    declared (fit on one, validated on the other): viscous and Coulomb friction found on every joint,
    within 5 %; armature where separable from the base parameters, within 12 %; the error a few %."""
    problem = load_problem(CONFIGS / "smoke.yaml")
    run_optimize(problem, tmp_path / "smoke.h5", force=True)
    done = run_rehearse(tmp_path / "smoke.h5", record=tmp_path / "runs", plot=tmp_path / "r.png")
    losses = problem.rehearsal.joint_losses
    runs = [{"file": str(p), "role": role} for p, role in zip(done.recordings, ("fit", "validation"))]
    config = panda_runs_config([]) | {"output": str(tmp_path / "id.h5")}
    config["data"]["runs"] = runs
    report = run_identification(load_problem(write_config(tmp_path, config, "id.yaml"), IdentifyProblem))[0]
    found = {(t.effect, report.joints[t.joint]): v for t, _, v, _ in report.effect_values()}
    truth = {"viscous": losses.damping, "coulomb": losses.frictionloss, "armature": losses.armature}
    for joint in report.joints:
        for effect in ("viscous", "coulomb"):
            assert found[(effect, joint)] == pytest.approx(truth[effect], rel=0.05), (effect, joint)
    armatures = [v for (effect, _), v in found.items() if effect == "armature"]
    assert len(armatures) >= 4 and all(v == pytest.approx(losses.armature, rel=0.12) for v in armatures)
    assert report.mean(report.relative_after) < 3.0 < report.mean(report.relative_before)  # %
