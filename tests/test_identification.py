"""Closing the loop: effect columns against closed forms, detection of undeclared effects on
simulated data with known parameters, no false effect, bad data, and the real Panda run."""

from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from conftest import CONFIGS, write_config
from excite_cli.cli import app
from excite_cli.config import load_problem
from excite_cli.identification.config import EFFECT_NAMES, IdentifyProblem
from excite_cli.identification.effects import COEFFICIENTS, effect_columns
from excite_cli.identification.pipeline import effect_values, run_identification
from excite_cli.identification.preprocessing import Filter, default_cutoff
from excite_cli.identification.measurements import load_run

runner = CliRunner()
HERE = Path(__file__).resolve().parent
SHARED = HERE.parent.parent / "shared" / "data" / "panda-gaz2019"
JOINTS = [f"panda_joint{k}" for k in range(1, 8)]
TRUE = {"coulomb": 0.6, "viscous": 0.4}
ARMATURE = {"panda_joint4": 0.1, "panda_joint6": 0.05}
NOISE = 0.05


def test_effect_columns_closed_forms():
    q = np.array([-1.0, 0.0, 0.5, 2.0])
    qd = np.array([-2.0, -1e-4, 0.3, 1.0])
    qdd = np.array([3.0, 0.0, -1.0, 0.2])
    rigid = np.array([5.0, -2.0, 0.5, 1.0])
    col = lambda e: effect_columns(e, q, qd, qdd, 0.01, 0.1, 0.02, rigid)
    np.testing.assert_allclose(col("coulomb")[:, 0], np.tanh(qd / 0.01))
    assert col("coulomb")[[0, 2, 3], 0] == pytest.approx([-1, 1, 1], abs=1e-10)  # sign(q̇) away from 0
    np.testing.assert_allclose(col("coulomb_asymmetric")[:, 0], np.abs(np.tanh(qd / 0.01)))
    np.testing.assert_allclose(col("viscous")[:, 0], qd)
    np.testing.assert_allclose(col("stribeck")[:, 0], np.tanh(qd / 0.01) * np.exp(-((qd / 0.1) ** 2)))
    np.testing.assert_allclose(col("offset")[:, 0], 1.0)
    np.testing.assert_allclose(col("armature")[:, 0], qdd)
    np.testing.assert_allclose(col("spring")[:, 0], q)
    np.testing.assert_allclose(col("gravity_compensator"), np.column_stack([np.sin(q), np.cos(q)]))
    np.testing.assert_allclose(col("position_2"), np.column_stack([np.sin(2 * q), np.cos(2 * q)]))
    np.testing.assert_allclose(col("viscous_asymmetric")[:, 0], np.abs(qd))
    np.testing.assert_allclose(col("load_coulomb")[:, 0], np.abs(rigid) * np.tanh(qd / 0.01))
    with pytest.raises(ValueError):
        effect_columns("load_coulomb", q, qd, qdd, 0.01, 0.1)
    for effect, names in COEFFICIENTS.items():
        assert col(effect).shape == (4, len(names))


def test_held_friction_holds_the_sign_of_the_last_motion():
    qd = np.array([0.0, 0.5, 0.01, 0.0, -0.3, -0.001, 0.005, 0.2, 0.0])
    z = np.zeros_like(qd)
    # at rest before any motion: 0; slow samples take the sign of the last fast one
    expected = [0.0, 0.0, 1.0, 1.0, 0.0, -1.0, -1.0, 0.0, 1.0]
    np.testing.assert_array_equal(effect_columns("held", z, qd, z, 0.01, 0.1, 0.02)[:, 0], expected)


def test_asymmetric_coulomb_gives_direction_dependent_levels():
    qd = np.array([-1.0, 1.0])
    fc, fa = 0.5, 0.1
    z = np.zeros(2)
    tau = fc * effect_columns("coulomb", z, qd, z, 0.01, 0.1)[:, 0] + fa * effect_columns("coulomb_asymmetric", z, qd, z, 0.01, 0.1)[:, 0]
    assert tau == pytest.approx([-(fc - fa), fc + fa])


@pytest.fixture(scope="module")
def optimized(tmp_path_factory):
    """A small optimized Panda result with 3 trajectories."""
    tmp = tmp_path_factory.mktemp("opt")
    data = yaml.safe_load((HERE.parent / "configs" / "smoke.yaml").read_text())
    data.update(sequence={"iterations": 3}, output=str(tmp / "panda.h5"))
    result = runner.invoke(app, ["optimize", str(write_config(tmp, data))])
    assert result.exit_code == 0, result.output
    return tmp / "panda.h5"


def _simulate_and_identify(tmp: Path, optimized: Path, effects: dict, candidates: list | None = None):
    # 8 periods per run and time blocks in every run: ~720 independent held-out samples per joint
    # at the 3 Hz cut-off, so each joint's RMS is known to ~2.6 % (1 sigma)
    sim = {"sample_rate": 500, "periods": 8, "timestamp_jitter": 0.1, "torque_noise": NOISE, "seed": 4, "effects": effects}
    result = runner.invoke(app, ["simulate", str(optimized), str(write_config(tmp, sim, "effects.yaml")), "-o", str(tmp)])
    assert result.exit_code == 0, result.output
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {"runs": [{"file": f"run_{k}.csv", "role": "blocks"} for k in (1, 2, 3)],
                 "columns": {"q": [f"q_{j}" for j in JOINTS], "tau": [f"tau_{j}" for j in JOINTS]}},
        "output": str(tmp / "ident.h5"),
    }
    if candidates is not None:
        config["identification"] = {"candidates": candidates}
    problem = load_problem(write_config(tmp, config, "identify.yaml"), IdentifyProblem)
    report, robot, base, _ = run_identification(problem)
    # noise level after the same preprocessing: white noise through the same filter
    runs = [load_run(r, problem.data, problem, 7) for r in problem.data.runs]
    rate = (runs[2].time.size - 1) / (runs[2].time[-1] - runs[2].time[0])
    from scipy import signal

    cutoff = default_cutoff(runs, problem.preprocessing)
    sos = signal.butter(4, cutoff, fs=rate, output="sos")
    noise = Filter(sos, rate, cutoff, 0, 1).low_pass(np.random.default_rng(0).normal(0, NOISE, (20000, 7)))
    return report, robot, base, float(noise.std())


def test_undeclared_friction_and_armature_are_found(tmp_path, optimized):
    effects = {"coulomb": {"*": TRUE["coulomb"]}, "viscous": {"*": TRUE["viscous"]}, "armature": ARMATURE}
    report, robot, base, noise_level = _simulate_and_identify(tmp_path, optimized, effects)
    expected = {(e, j) for e in TRUE for j in JOINTS} | {("armature", j) for j in ARMATURE}
    found = {(e, j) for e, _, j, _, _ in effect_values(report)}
    assert found == expected
    for effect, _, joint, value, std in effect_values(report):
        truth = ARMATURE[joint] if effect == "armature" else TRUE[effect]
        assert abs(value - truth) <= max(0.05 * truth, 3 * std)
    # rigid-body base parameters: the URDF's
    truth = base.from_standard(robot.urdf_parameters())
    estimate, std = report.selection.fit.x[: base.count], report.selection.fit.std[: base.count]
    assert np.linalg.norm(estimate - truth) < 0.01 * np.linalg.norm(truth)
    assert np.mean(np.abs(estimate - truth) <= 3 * std) > 0.95  # deviations account for the filtering
    assert np.all(np.abs(report.rms_after - noise_level) <= 0.1 * noise_level)
    assert np.all(report.rms_before >= 3 * report.rms_after)


@pytest.mark.parametrize("candidates", [None, list(EFFECT_NAMES)])
def test_no_effect_in_the_data_adds_none(tmp_path, optimized, candidates):
    report, *_ = _simulate_and_identify(tmp_path, optimized, {}, candidates)
    assert report.selection.effects == []
    assert np.allclose(report.rms_before, report.rms_after)


def test_identify_command_writes_report_and_prior(tmp_path, optimized):
    effects = {"coulomb": {"*": 0.5}}
    _simulate_and_identify(tmp_path, optimized, effects)
    config = yaml.safe_load((tmp_path / "identify.yaml").read_text())
    config["identification"] = {"declared_effects": {"panda_joint1": ["viscous"]}}  # not in the data
    result = runner.invoke(app, ["identify", str(write_config(tmp_path, config, "identify.yaml"))], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "before [Nm]" in result.output and "coulomb" in result.output
    with h5py.File(tmp_path / "ident.h5") as f:
        g = f["identification"]
        assert g["rms_after"].shape == (7,) and np.all(g["rms_after"][()] < g["rms_before"][()])
        effects = g["effects"][()]
        assert {e.decode() for e in effects["effect"]} == {"coulomb", "viscous"}
        declared = effects[effects["declared"]]
        assert len(declared) == 1 and declared["joint"][0].decode() == "panda_joint1" and declared["order"][0] == 1
        assert abs(declared["value"][0]) < 3 * declared["std"][0] + 1e-3  # declared but absent: ~0
        assert f["regressor"].shape[1] == g["base_parameters"].shape[0]
    assert (tmp_path / "ident_residuals.png").stat().st_size > 20000
    # the measured regressor serves as prior data C0 of optimize (Eq. 41)
    data = yaml.safe_load((HERE.parent / "configs" / "smoke.yaml").read_text())
    data.update(sequence={"iterations": 1, "prior": str(tmp_path / "ident.h5")}, optimizer={"max_iterations": 10, "restarts": 1})
    result = runner.invoke(app, ["optimize", str(write_config(tmp_path, data, "prior.yaml")), "-o", str(tmp_path / "p.h5")])
    assert result.exit_code == 0, result.output


def _bad_csv(tmp_path, text: str, columns=None, crop=None):
    (tmp_path / "bad.csv").write_text(text)
    run = {"file": "bad.csv", "role": "blocks"}
    if crop:
        run["crop"] = crop
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {"runs": [run], "columns": columns or {"q": [f"q{k}" for k in range(1, 8)], "tau": [f"t{k}" for k in range(1, 8)]}},
        "output": str(tmp_path / "out.h5"),
    }
    result = runner.invoke(app, ["identify", str(write_config(tmp_path, config, "bad.yaml"))])
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert not (tmp_path / "out.h5").exists()
    return " ".join(result.output.split())


def _csv(rows: int, nan_at=None, repeat_time_at=None):
    header = "time," + ",".join(f"q{k}" for k in range(1, 8)) + "," + ",".join(f"t{k}" for k in range(1, 8))
    t = np.arange(rows) * 0.001
    if repeat_time_at is not None:
        t[repeat_time_at] = t[repeat_time_at - 1]
    values = np.column_stack([t, np.sin(np.outer(t, np.arange(1, 15)))])
    if nan_at is not None:
        values[nan_at, 3] = np.nan
    lines = [header] + [",".join("" if np.isnan(v) else f"{v:.6g}" for v in row) for row in values]
    return "\n".join(lines) + "\n"


def test_bad_data_gets_one_clear_message(tmp_path):
    assert "NaN or missing value in q at data row 6" in _bad_csv(tmp_path, _csv(3000, nan_at=5))
    assert "time is not strictly increasing at data row 11" in _bad_csv(tmp_path, _csv(3000, repeat_time_at=10))
    assert "data.columns.q: 6 columns for the robot's 7 active joints" in _bad_csv(
        tmp_path, _csv(3000), {"q": [f"q{k}" for k in range(1, 7)], "tau": [f"t{k}" for k in range(1, 8)]})
    assert "has no column 'q9'" in _bad_csv(
        tmp_path, _csv(3000), {"q": [f"q{k}" for k in range(1, 7)] + ["q9"], "tau": [f"t{k}" for k in range(1, 8)]})
    assert "fewer than the" in _bad_csv(tmp_path, _csv(3000), crop=[0.0, 0.05])


def test_unknown_joint_in_declared_effects(tmp_path):
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {"runs": [{"file": "x.csv"}], "columns": {"q": [f"q{k}" for k in range(1, 8)], "tau": [f"t{k}" for k in range(1, 8)]}},
        "identification": {"declared_effects": {"panda_joint9": ["viscous"]}},
    }
    (tmp_path / "x.csv").write_text(_csv(3000))
    result = runner.invoke(app, ["identify", str(write_config(tmp_path, config, "j.yaml"))])
    assert result.exit_code == 2
    assert "identification.declared_effects: 'panda_joint9' is not an active joint" in result.output


@pytest.mark.skipif(not (SHARED / "exciting_traj_1.csv").exists(), reason="shared Panda data not present")
def test_real_panda_run(tmp_path):
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {"runs": [{"file": str(SHARED / "exciting_traj_1.csv"), "role": "blocks"}],
                 "columns": {"q": [f"q{k}" for k in range(1, 8)], "qd": [f"dq{k}" for k in range(1, 8)],
                             "tau": [f"tau{k}" for k in range(1, 8)]}},
    }
    report, *_ = run_identification(load_problem(write_config(tmp_path, config), IdentifyProblem))
    assert report.selection.effects  # real joints have friction
    assert np.all(report.rms_after <= report.rms_before + 1e-9)
    assert report.rms_after[6] < 0.5 * report.rms_before[6]  # the wrist is friction-dominated


@pytest.mark.skipif(not (SHARED / "exciting_traj_1.csv").exists(), reason="shared Panda data not present")
def test_real_panda_unseen_phase_at_5_hz_reports_the_selected_model():
    problem = load_problem(HERE.parent / "configs" / "panda_identify_phase.yaml", IdentifyProblem)
    problem.data.runs = [run.model_copy(update={"file": str(SHARED / "exciting_traj_1.csv")}) for run in problem.data.runs]
    problem.preprocessing.cutoff = 5.0
    report, *_ = run_identification(problem)
    selection, val = report.selection, report.validation
    # the reported model is the one the selection scored: same weights, same held-out error
    weights = 1.0 / selection.rigid.sigma[val.joint]
    scored = np.sum((weights * (val.tau - report.predicted_after.ravel())) ** 2)
    assert scored == pytest.approx(selection.steps[-1]["validation_sse"], rel=1e-6)
    # at 5 Hz the F-test fails the best-ranked candidate early; the search goes on with the next
    # ones instead of stopping at one effect (27.9 % mean error before)
    assert len(selection.effects) >= 5 and report.relative_after.mean() < 20.0


NEW_EFFECTS = {
    "held": {"held": {"panda_joint4": 1.0}},
    "load_coulomb": {"load_coulomb": {"panda_joint2": 0.05, "panda_joint4": 0.05}},
    "position_2": {"position_2": {"panda_joint1": [0.3, 0.2]}},
    "offset": {"offset": {"panda_joint3": 0.5}},
    "viscous_asymmetric": {"viscous": {"panda_joint5": 0.3}, "viscous_asymmetric": {"panda_joint5": 0.1}},
}


@pytest.mark.parametrize("case", list(NEW_EFFECTS))
def test_each_undeclared_effect_is_named_with_its_value(tmp_path, optimized, case):
    effects = NEW_EFFECTS[case]
    report, *_ = _simulate_and_identify(tmp_path, optimized, effects, list(EFFECT_NAMES))  # all twelve candidates
    truth = {(e, c, j): v for e, per_joint in effects.items() for j, value in per_joint.items()
             for c, v in zip(COEFFICIENTS[e], np.atleast_1d(value))}
    found = {(e, c, j): (value, std) for e, c, j, value, std in effect_values(report)}
    assert {(e, j) for e, _, j in found} == {(e, j) for e, _, j in truth}, found
    for key, value in truth.items():
        estimate, std = found[key]
        assert abs(estimate - value) <= max(0.05 * abs(value), 3 * std), (key, estimate, std)


@pytest.mark.skipif(not (SHARED / "exciting_traj_1.csv").exists(), reason="shared Panda data not present")
def test_validate_scores_a_report_on_other_runs(tmp_path):
    config = yaml.safe_load((HERE.parent / "configs" / "panda_identify_phase.yaml").read_text())
    for run in config["data"]["runs"]:
        run["file"] = str(SHARED / "exciting_traj_1.csv")
    config["output"] = str(tmp_path / "phase.h5")
    identify = load_problem(write_config(tmp_path, config, "phase.yaml"), IdentifyProblem)
    report, *_ = run_identification(identify)
    result = runner.invoke(app, ["identify", str(tmp_path / "phase.yaml")], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    # the held-out phase again: exactly identify's validation errors; the whole run: its own
    config["data"]["runs"] = [{"file": str(SHARED / "exciting_traj_1.csv"), "crop": [7.8, 13.2]},
                              {"file": str(SHARED / "exciting_traj_1.csv")}]
    from excite_cli.identification.validate import validate_model

    errors = validate_model(tmp_path / "phase.h5", load_problem(write_config(tmp_path, config, "val.yaml"), IdentifyProblem))
    np.testing.assert_allclose(errors[0].relative, report.relative_after, rtol=1e-9)
    assert errors[1].instants > 3 * errors[0].instants and errors[1].relative.mean() < report.relative_before.mean()
    result = runner.invoke(app, ["validate", str(tmp_path / "phase.h5"), str(tmp_path / "val.yaml")], env={"COLUMNS": "200"})
    assert result.exit_code == 0 and "[7.8, 13.2] s" in result.output
    # a report of other joints, and a file that is not a report: one message each
    config["robot"]["active_joints"] = JOINTS[:6]
    config["data"]["columns"] = {"q": [f"q{k}" for k in range(1, 7)], "tau": [f"tau{k}" for k in range(1, 7)]}
    result = runner.invoke(app, ["validate", str(tmp_path / "phase.h5"), str(write_config(tmp_path, config, "other.yaml"))])
    assert result.exit_code == 2 and "other joints" in result.output
    result = runner.invoke(app, ["validate", str(HERE / "panda_capsules.yaml"), str(tmp_path / "val.yaml")])
    assert result.exit_code == 2 and "Traceback" not in result.output


@pytest.mark.skipif(not (SHARED / "exciting_traj_1.csv").exists(), reason="shared Panda data not present")
def test_report_has_per_run_validation_errors(tmp_path):
    config = yaml.safe_load((HERE.parent / "configs" / "panda_identify_phase.yaml").read_text())
    runs = config["data"]["runs"]
    for run in runs:
        run["file"] = str(SHARED / "exciting_traj_1.csv")
    runs[2:] = [{"file": str(SHARED / "exciting_traj_1.csv"), "crop": crop, "role": "validation"}
                for crop in ([7.8, 10.5], [10.5, 13.2])]  # the unseen phase as two runs
    config["output"] = str(tmp_path / "r.h5")
    result = runner.invoke(app, ["identify", str(write_config(tmp_path, config, "r.yaml"))], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    with h5py.File(tmp_path / "r.h5") as f:
        table = f["identification/validation_runs"][()]
        rms_after = f["identification/rms_after"][()]
    assert [r.decode() for r in table["run"]] == ["exciting_traj_1.csv [7.8, 10.5] s", "exciting_traj_1.csv [10.5, 13.2] s"]
    # the runs' mean squared errors, weighted by their instants, make up the whole validation's
    total = (table["instants"][:, None] * table["rms_after"] ** 2).sum(axis=0) / table["instants"].sum()
    np.testing.assert_allclose(np.sqrt(total), rms_after, rtol=1e-9)


def test_shipped_simulated_runs_give_back_their_undeclared_friction():
    """data/panda_simulated (shipped, no ../shared needed): Coulomb 0.6 Nm and viscous 0.4 Nm·s/rad on
    every joint, undeclared in configs/panda_identify_simulated.yaml."""
    problem = load_problem(CONFIGS / "panda_identify_simulated.yaml", IdentifyProblem)
    report, *_ = run_identification(problem)
    assert {(e, report.joints[j]) for e, j in report.selection.effects} == {(e, j) for e in ("coulomb", "viscous") for j in JOINTS}
    for effect, _, joint, value, std in effect_values(report):
        assert value == pytest.approx({"coulomb": 0.6, "viscous": 0.4}[effect], rel=0.15), (effect, joint)
    assert report.relative_before.mean() > 30.0 and report.relative_after.mean() < 5.0
