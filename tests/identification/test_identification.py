"""Closing the loop: effect columns against closed forms, detection of undeclared effects on
simulated data with known parameters, no false effect, bad data, and the real Panda run."""

from pathlib import Path

import h5py
import mujoco
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import CONFIGS, JOINTS, NOISE, SHARED, TESTS, panda_runs_config, robot_of, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.effects import EFFECTS
from excite_cli.h5 import read_strings, write_strings
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.effects import effect_columns
from excite_cli.identification.fitting.dataset import run_offset_columns
from excite_cli.identification.measured.measurements import load_run
from excite_cli.identification.measured.preprocessing import Filter
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.identification.validate import validate_model
from excite_cli.trajectory.fourier import FourierTrajectory
from excite_cli.workflows.identify import run_identify, write_identified_mjcf
from excite_cli.workflows.simulate import simulate_runs

runner = CliRunner()
HERE = TESTS
TRUE = {"coulomb": 0.6, "viscous": 0.4}
ARMATURE = {"panda_joint4": 0.1, "panda_joint6": 0.05}


def test_effect_columns_closed_forms():
    q = np.array([-1.0, 0.0, 0.5, 2.0])
    qd = np.array([-2.0, -1e-4, 0.3, 1.0])
    qdd = np.array([3.0, 0.0, -1.0, 0.2])
    rigid = np.array([5.0, -2.0, 0.5, 1.0])
    col = lambda e, shape=None: effect_columns(e, q, qd, qdd, 0.01, shape, rigid)  # noqa: E731
    np.testing.assert_allclose(col("coulomb")[:, 0], np.tanh(qd / 0.01))
    assert col("coulomb")[[0, 2, 3], 0] == pytest.approx([-1, 1, 1], abs=1e-10)  # sign(q̇) away from 0
    np.testing.assert_allclose(col("coulomb_asymmetric")[:, 0], np.abs(np.tanh(qd / 0.01)))
    np.testing.assert_allclose(col("viscous")[:, 0], qd)
    np.testing.assert_allclose(col("stribeck", 0.1)[:, 0], np.tanh(qd / 0.01) * np.exp(-((qd / 0.1) ** 2)))
    np.testing.assert_allclose(col("stribeck", 0.5)[:, 0], np.tanh(qd / 0.01) * np.exp(-((qd / 0.5) ** 2)))
    np.testing.assert_allclose(col("offset")[:, 0], 1.0)
    np.testing.assert_allclose(col("armature")[:, 0], qdd)
    np.testing.assert_allclose(col("spring")[:, 0], q)
    np.testing.assert_allclose(col("gravity_compensator"), np.column_stack([np.sin(q), np.cos(q)]))
    np.testing.assert_allclose(col("position_2"), np.column_stack([np.sin(2 * q), np.cos(2 * q)]))
    np.testing.assert_allclose(col("viscous_asymmetric")[:, 0], np.abs(qd))
    np.testing.assert_allclose(col("load_coulomb")[:, 0], np.abs(rigid) * np.tanh(qd / 0.01))
    with pytest.raises(ValueError):
        effect_columns("load_coulomb", q, qd, qdd, 0.01)
    with pytest.raises(ValueError):
        effect_columns("held", q, qd, qdd, 0.01)  # a shape effect needs its velocity
    for effect in EFFECTS.values():  # one column per coefficient, units for each
        assert col(effect.name, 0.1).shape == (4, len(effect.coefficients)) == (4, len(effect.units))


def test_held_friction_holds_the_sign_of_the_last_motion():
    qd = np.array([0.0, 0.5, 0.01, 0.0, -0.3, -0.001, 0.005, 0.2, 0.0])
    z = np.zeros_like(qd)
    # at rest before any motion: 0; slow samples take the sign of the last fast one
    expected = [0.0, 0.0, 1.0, 1.0, 0.0, -1.0, -1.0, 0.0, 1.0]
    np.testing.assert_array_equal(effect_columns("held", z, qd, z, 0.01, 0.02)[:, 0], expected)
    # a wider hold velocity holds the sign longer: 0.2 rad/s is itself below 0.25
    np.testing.assert_array_equal(effect_columns("held", z, qd, z, 0.01, 0.25)[:, 0], [0, 0, 1, 1, 0, -1, -1, -1, -1])


def test_asymmetric_coulomb_gives_direction_dependent_levels():
    qd = np.array([-1.0, 1.0])
    fc, fa = 0.5, 0.1
    z = np.zeros(2)
    tau = (
        fc * effect_columns("coulomb", z, qd, z, 0.01)[:, 0]
        + fa * effect_columns("coulomb_asymmetric", z, qd, z, 0.01)[:, 0]
    )
    assert tau == pytest.approx([-(fc - fa), fc + fa])


def test_run_offsets_are_indicators_or_the_mean_for_an_unfitted_run():
    np.testing.assert_array_equal(run_offset_columns(2, [0, 2], 3, 2), [[0, 1]] * 3)
    np.testing.assert_array_equal(run_offset_columns(1, [0, 2], 2, 2), [[0.5, 0.5]] * 2)


def _simulate(
    tmp: Path, optimized: Path, effects: dict, candidates: list | None = None, settings: dict | None = None, **extra
) -> IdentifyProblem:
    """Three simulated runs of ``optimized`` with ``effects`` in ``tmp`` and their identify config
    (``identify.yaml``, with ``candidates`` and other identification ``settings``), loaded."""
    # 8 periods per run and time blocks in every run: ~720 independent held-out samples per joint
    # at the 5 Hz cut-off, so each joint's RMS is known to ~2.6 % (1 sigma)
    sim = {
        "sample_rate": 500,
        "periods": 8,
        "timestamp_jitter": 0.1,
        "torque_noise": NOISE,
        "seed": 4,
        "effects": effects,
        **extra,
    }
    result = runner.invoke(
        app, ["simulate", str(optimized), str(write_config(tmp, sim, "effects.yaml")), "-o", str(tmp), "--force"]
    )
    assert result.exit_code == 0, result.output
    identification = {**(settings or {}), **({"candidates": candidates} if candidates is not None else {})}
    config = {
        **panda_runs_config([f"run_{k}.csv" for k in (1, 2, 3)], **identification),
        "output": str(tmp / "ident.h5"),
    }
    return load_problem(write_config(tmp, config, "identify.yaml"), IdentifyProblem)


def _simulate_and_identify(
    tmp: Path,
    optimized: Path,
    effects: dict,
    candidates: list | None = None,
    consistent: bool = False,
    settings: dict | None = None,
    **sim_extra,
):
    """:func:`_simulate` and identify (the consistent fit beside with ``consistent``): report, robot,
    base, the torque noise level after preprocessing [Nm] and the problem."""
    problem = _simulate(tmp, optimized, effects, candidates, settings, **sim_extra)
    report, robot, base, _ = run_identification(problem, consistent_beside=consistent)
    # noise level after the same preprocessing: white noise through the same filter
    runs = [load_run(r, problem.data, problem.robot.active_joints, problem.folder) for r in problem.data.runs]
    rate = (runs[2].time.size - 1) / (runs[2].time[-1] - runs[2].time[0])
    from scipy import signal

    sos = signal.butter(4, report.cutoff, fs=rate, output="sos")
    noise = Filter(sos, rate, report.cutoff, 0, 1).low_pass(np.random.default_rng(0).normal(0, NOISE, (20000, 7)))
    return report, robot, base, float(noise.std()), problem


def _found(report) -> dict:
    """{(effect, coefficient, joint): (value, std, shape)} of the report's effects."""
    return {(t.effect, c, report.joints[t.joint]): (v, s, t.shape) for t, c, v, s in report.effect_values()}


@pytest.mark.end_to_end
def test_undeclared_friction_and_armature_are_found_and_written_to_mjcf(tmp_path, optimized):
    effects = {"coulomb": {"*": TRUE["coulomb"]}, "viscous": {"*": TRUE["viscous"]}, "armature": ARMATURE}
    report, robot, base, noise_level, problem = _simulate_and_identify(tmp_path, optimized, effects, consistent=True)
    expected = {(e, j) for e in TRUE for j in JOINTS} | {("armature", j) for j in ARMATURE}
    assert {(e, j) for e, _, j in _found(report)} == expected
    for (effect, _, joint), (value, std, _) in _found(report).items():
        truth = ARMATURE[joint] if effect == "armature" else TRUE[effect]
        assert abs(value - truth) <= max(0.05 * truth, 3 * std)
    # rigid-body base parameters: the URDF's
    truth = base.from_standard(robot.urdf_parameters())
    estimate, std = report.selection.fit.x[: base.count], report.selection.fit.std[: base.count]
    assert np.linalg.norm(estimate - truth) < 0.01 * np.linalg.norm(truth)
    assert np.mean(np.abs(estimate - truth) <= 3 * std) > 0.95  # deviations account for the filtering
    assert np.all(np.abs(report.rms_after - noise_level) <= 0.1 * noise_level)
    # the MJCF for MuJoCo: MuJoCo reads the simulated armature and friction back from its own joint
    # fields, its inverse dynamics is excite's, its validation error within 1 point of excite's
    model, check = write_identified_mjcf(problem, report, robot, base, tmp_path / "panda.xml")
    mj = mujoco.MjModel.from_xml_path(str(tmp_path / "panda.xml"))
    for joint in JOINTS:
        dof = mj.joint(joint).dofadr[0]
        assert mj.dof_frictionloss[dof] == pytest.approx(TRUE["coulomb"], rel=0.05)
        assert mj.dof_damping[dof] == pytest.approx(TRUE["viscous"], rel=0.05)
        # joints 1-2 carry the rotors the consistent fit holds apart (none in the data: near 0)
        assert mj.dof_armature[dof] == pytest.approx(ARMATURE.get(joint, 0.0), rel=0.05, abs=1e-3)
    assert model.unwritten == [] and check.unwritten == []
    assert check.rigid <= 1e-5 and check.friction <= 1e-5
    # MuJoCo's friction follows q̈ + b q̇ near velocity reversals (friction_differs), so its error on the
    # light wrists, whose torque is mostly friction, depends on how often they reverse (joint 6: 9.9 %
    # against excite's 0.3 % on the smoke trajectories, 12 % of the entries differing); on the arm's
    # four heavy joints friction is a small part of the torque and the two agree within a point
    assert np.all(np.abs(check.relative_mujoco[:4] - check.relative_excite[:4]) <= 1.0)
    assert 0.0 < check.friction_differs < 50.0
    np.testing.assert_allclose(check.relative_written, check.relative_excite, rtol=1e-12)
    assert np.all(report.rms_before >= 3 * report.rms_after)


@pytest.mark.end_to_end
def test_no_effect_in_the_data_adds_none(tmp_path, optimized):
    report, *_ = _simulate_and_identify(tmp_path, optimized, {})  # the default candidates: every effect
    assert report.selection.terms == []
    # the rigid-body model; its fit may be the consistent one (chosen with the model), within 1 %
    assert np.allclose(report.rms_before, report.rms_after, rtol=0.01 if report.fit_choice.is_consistent else 1e-5)


#: Each effect undeclared in simulated data (with the simulation's shape velocities), found with the
#: default candidates (the position-dependent ones among them since issue 42, here at the price of the
#: others: at the default position_improvement the 0.4 / −0.3 Nm sin/cos term on joint 1 is taken as
#: a per-run offset, −0.23 to −0.07 Nm; bench/identify_transfer.py finds a spring with the defaults).
#: An undeclared offset is found, one per run, by test_offsets_per_run_and_a_known_payload.
NEW_EFFECTS = {
    "held": ({"held": {"panda_joint4": 1.0}}, {"held_velocity": 0.1}),
    "load_coulomb": ({"load_coulomb": {"panda_joint2": 0.05, "panda_joint4": 0.05}}, {}),
    "viscous_asymmetric": ({"viscous": {"panda_joint5": 0.3}, "viscous_asymmetric": {"panda_joint5": 0.1}}, {}),
    "stribeck": ({"coulomb": {"panda_joint6": 0.4}, "stribeck": {"panda_joint6": 0.3}}, {"stribeck_velocity": 0.2}),
    "gravity_compensator": ({"gravity_compensator": {"panda_joint1": [0.4, -0.3]}}, {}),
    "position_2": ({"position_2": {"panda_joint1": [0.3, 0.2]}}, {}),
}


@pytest.mark.end_to_end
@pytest.mark.parametrize("case", list(NEW_EFFECTS))
def test_each_undeclared_effect_is_named_with_its_value_and_shape(tmp_path, optimized, case):
    effects, shapes = NEW_EFFECTS[case]
    price = {"position_improvement": 0.02} if EFFECTS[case].position else {}
    report, *_ = _simulate_and_identify(tmp_path, optimized, effects, settings=price, **shapes)
    truth = {
        (e, c, j): v
        for e, per_joint in effects.items()
        for j, value in per_joint.items()
        for c, v in zip(EFFECTS[e].coefficients, np.atleast_1d(value))
    }
    found = _found(report)
    assert {(e, j) for e, _, j in found} == {(e, j) for e, _, j in truth}, found
    for (effect, coefficient, joint), (value, std, shape) in found.items():
        expected = truth[(effect, coefficient.split("[")[0], joint)]  # an offset per run: tau0[run] each
        assert abs(value - expected) <= max(0.05 * abs(expected), 3 * std), (effect, joint, value, std)
        if EFFECTS[effect].shape:  # the profile search picks the simulated velocity from the grid
            assert shape == shapes[EFFECTS[effect].shape_field]


@pytest.mark.end_to_end
def test_offsets_per_run_and_a_known_payload(tmp_path, optimized):
    """Two runs with different torque offsets on joint 3 and a 1.5 kg payload on the flange in the
    first: the payload's torque (pinocchio RNEA with the payload added to link 7, independent of
    the regressor the identification uses) is taken out, and each run gets its own offset."""
    payload = {
        "mass": 1.5,
        "com": [0.0, 0.02, 0.1],
        "inertia": [0.004, 0.0, 0.004, 0.0, 0.0, 0.002],
        "frame": "panda_hand",
    }
    for prefix, offset in (("a", 0.4), ("b", -0.3)):
        simulate_runs(
            optimized,
            SimulationConfig(
                sample_rate=500,
                periods=8,
                torque_noise=NOISE,
                seed=len(prefix + str(offset)),
                effects={"offset": {"panda_joint3": offset}},
            ),
            tmp_path,
            prefix,
        )
    robot = robot_of(load_problem(CONFIGS / "panda_joint_limits.yaml"))
    loaded = robot.model.copy()
    frame = loaded.frames[loaded.getFrameId("panda_hand")]
    xx, xy, yy, xz, yz, zz = payload["inertia"]
    loaded.inertias[frame.parentJoint] += frame.placement.act(
        pin.Inertia(1.5, np.array(payload["com"]), np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]))
    )
    table = np.loadtxt(tmp_path / "a_1.csv", delimiter=",", skiprows=1)
    with h5py.File(optimized) as f:
        problem = yaml.safe_load(f.attrs["config"])
        trajectory = FourierTrajectory(problem["trajectory"]["harmonics"], problem["trajectory"]["base_frequency"])
        alpha = f["iterations/1/alpha"][()]
    q, qd, qdd = trajectory.basis(table[:, 0]).evaluate(alpha)
    data = loaded.createData()
    extra = np.array([pin.rnea(loaded, data, *robot.state(*x)) - robot.torques(*x) for x in zip(q, qd, qdd)])[
        :, robot.v_idx
    ]
    table[:, 8:] += extra
    np.savetxt(
        tmp_path / "a_1.csv",
        table,
        delimiter=",",
        header=(tmp_path / "b_1.csv").read_text().splitlines()[0],
        comments="",
    )
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {
            "runs": [{"file": "a_1.csv", "role": "blocks", "payload": payload}, {"file": "b_1.csv", "role": "blocks"}],
            "columns": {"q": [f"q_{j}" for j in JOINTS], "tau": [f"tau_{j}" for j in JOINTS]},
        },
    }
    report, robot, base, _ = run_identification(
        load_problem(write_config(tmp_path, config, "two.yaml"), IdentifyProblem)
    )
    found = _found(report)
    assert {(e, j) for e, _, j in found} == {("offset", "panda_joint3")}, found
    values = {c: (v, s) for (_, c, _), (v, s, _) in found.items()}
    for name, truth in (("tau0[a_1.csv]", 0.4), ("tau0[b_1.csv]", -0.3)):
        assert abs(values[name][0] - truth) <= max(0.05 * abs(truth), 3 * values[name][1])
    truth = base.from_standard(robot.urdf_parameters())
    assert np.linalg.norm(report.selection.fit.x[: base.count] - truth) < 0.01 * np.linalg.norm(truth)
    # the same data without the payload declared: the robot seems to carry it (its base parameters move)
    config["data"]["runs"][0].pop("payload")
    plain, *_ = run_identification(load_problem(write_config(tmp_path, config, "plain.yaml"), IdentifyProblem))
    assert np.linalg.norm(plain.selection.fit.x[: base.count] - truth) > 0.02 * np.linalg.norm(truth)


@pytest.mark.end_to_end
def test_identify_command_writes_report_and_prior(tmp_path, optimized):
    # viscous friction on one joint: every search (declared, Coulomb, Coulomb and viscous) must move
    _simulate(tmp_path, optimized, {"coulomb": {"*": 0.5}, "viscous": {"panda_joint4": 0.3}})
    config = yaml.safe_load((tmp_path / "identify.yaml").read_text())
    config["identification"] = {"declared_effects": {"panda_joint1": ["viscous"]}}  # not in the data
    result = runner.invoke(
        app, ["identify", str(write_config(tmp_path, config, "identify.yaml"))], env={"COLUMNS": "200"}
    )
    assert result.exit_code == 0, result.output
    assert "before [Nm]" in result.output and "coulomb" in result.output and "Selection steps" in result.output
    with h5py.File(tmp_path / "ident.h5") as f:
        g = f["identification"]
        assert g["rms_after"].shape == (7,) and np.all(g["rms_after"][()] < g["rms_before"][()])
        effects = g["effects"][()]
        assert {e.decode() for e in effects["effect"]} == {"coulomb", "viscous"}
        assert {u.decode() for u in effects["unit"]} == {"Nm", "Nm·s/rad"}
        declared = effects[effects["declared"]]
        assert len(declared) == 1 and declared["joint"][0].decode() == "panda_joint1" and declared["order"][0] == 1
        value, std = declared["value"][0], declared["std"][0]
        # declared but absent: held at its bound 0 (no two-sided std), or within 3 std of 0
        assert (value == 0.0 and np.isnan(std)) or abs(value) < 3 * std + 1e-3
        assert f["regressor"].shape[1] == g["base_parameters"].shape[0] and f["regressor"].compression == "gzip"
        assert yaml.safe_load(f.attrs["config"])["identification"]["folds"] == 6  # the effective config
        # the ladder ends at the reported model; steps and every candidate tried are stored
        ladder, steps, tried = g["ladder"][()], g["steps"][()], g["candidates"][()]
        assert ladder["step"][0].decode() == "rigid body"
        assert ladder["validation_error"][0] == pytest.approx(g["relative_before"][()].mean(), rel=1e-9)
        assert ladder["validation_error"][-1] == pytest.approx(g["relative_after"][()].mean(), rel=1e-9)
        assert ladder["cv_error"][-1] == pytest.approx(g.attrs["cv_error"], rel=1e-12)
        assert len(steps) >= 1 and set(tried["step"]) == set(steps["step"]) and len(tried) > 10 * len(steps)
        # an addition or a shape move buys its price (min_improvement, 2 %; a coupled effect's
        # coupling_improvement, 20 %); a removal saves its price and may cost up to it
        grows = np.array([m.decode() != "remove" for m in steps["move"]])
        coupled = np.array([" + " in j.decode() or " − " in j.decode() for j in steps["joint"]])
        price = np.where(coupled, 0.2, 0.02)
        assert np.all(steps["gain"][grows] > 100 * (1 - 1 / (1 + price[grows])) - 1e-9)
        assert np.all(steps["gain"][~grows] > -100 * price[~grows] - 1e-9)
        assert "min_improvement" in g.attrs["stop_reason"]
        v = g["validation"]
        assert v["measured"].shape == v["predicted_after"].shape == (g.attrs["validation_samples"], 7)
    assert (tmp_path / "ident_residuals.png").stat().st_size > 20000
    assert (tmp_path / "ident_ladder.png").stat().st_size > 20000
    # the measured regressor serves as prior data C0 of optimize (Eq. 41)
    data = yaml.safe_load((HERE.parent / "configs" / "smoke.yaml").read_text())
    data.update(
        sequence={"iterations": 1, "prior": str(tmp_path / "ident.h5")}, optimizer={"max_iterations": 10, "restarts": 1}
    )
    result = runner.invoke(
        app, ["optimize", str(write_config(tmp_path, data, "prior.yaml")), "-o", str(tmp_path / "p.h5")]
    )
    assert result.exit_code == 0, result.output


def _bad_csv(tmp_path, text: str, columns=None, crop=None):
    (tmp_path / "bad.csv").write_text(text)
    run = {"file": "bad.csv", "role": "blocks"}
    if crop:
        run["crop"] = crop
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {
            "runs": [run],
            "columns": columns or {"q": [f"q{k}" for k in range(1, 8)], "tau": [f"t{k}" for k in range(1, 8)]},
        },
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
        tmp_path, _csv(3000), {"q": [f"q{k}" for k in range(1, 7)], "tau": [f"t{k}" for k in range(1, 8)]}
    )
    assert "has no column 'q9'" in _bad_csv(
        tmp_path, _csv(3000), {"q": [f"q{k}" for k in range(1, 7)] + ["q9"], "tau": [f"t{k}" for k in range(1, 8)]}
    )
    assert "bad.csv lasts 0.05 s, under the 2 s a run needs" in _bad_csv(tmp_path, _csv(3000), crop=[0.0, 0.05])


def test_unknown_joint_in_declared_effects(tmp_path):
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {
            "runs": [{"file": "x.csv"}],
            "columns": {"q": [f"q{k}" for k in range(1, 8)], "tau": [f"t{k}" for k in range(1, 8)]},
        },
        "identification": {"declared_effects": {"panda_joint9": ["viscous"]}},
    }
    (tmp_path / "x.csv").write_text(_csv(3000))
    result = runner.invoke(app, ["identify", str(write_config(tmp_path, config, "j.yaml"))])
    assert result.exit_code == 2
    assert "identification.declared_effects: 'panda_joint9' is not an active joint" in result.output


@pytest.mark.skipif(not (SHARED / "exciting_traj_1.csv").exists(), reason="shared Panda data not present")
@pytest.mark.end_to_end
def test_real_panda_run(tmp_path):
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {
            "runs": [{"file": str(SHARED / "exciting_traj_1.csv"), "role": "blocks"}],
            "columns": {
                "q": [f"q{k}" for k in range(1, 8)],
                "qd": [f"dq{k}" for k in range(1, 8)],
                "tau": [f"tau{k}" for k in range(1, 8)],
            },
        },
    }
    report, *_ = run_identification(load_problem(write_config(tmp_path, config), IdentifyProblem))
    assert report.selection.terms  # real joints have friction
    assert np.all(report.rms_after <= report.rms_before + 1e-9)
    assert report.rms_after[6] < 0.5 * report.rms_before[6]  # the wrist is friction-dominated
    assert report.relative_after.mean() < 6.0  # blocks split: 25.4 % rigid body, 3.9 % measured


@pytest.mark.skipif(not (SHARED / "exciting_traj_1.csv").exists(), reason="shared Panda data not present")
@pytest.mark.end_to_end
def test_real_panda_fitted_on_a_short_first_phase_reports_the_fit_that_transfers():
    """Issue 42's analogue of a poorly excited fit run: the first 20 % of the real run fitted, the rest
    validated. Least squares' cross-validated error is the lower one on its search's model, yet it
    predicts the rest of the run worse; the default reports the physically consistent fit, within a
    point of the better of its two fits on the unseen motion (it was least squares: 9.9 against 7.6 %)."""
    problem = load_problem(HERE.parent / "configs" / "panda_identify_phase.yaml", IdentifyProblem)
    fit, _, validation = problem.data.runs
    problem.data.runs = [
        fit.model_copy(update={"file": str(SHARED / "exciting_traj_1.csv"), "crop": (0.0, 4.2)}),
        validation.model_copy(update={"file": str(SHARED / "exciting_traj_1.csv"), "crop": (4.4, 21.0)}),
    ]
    report = run_identification(problem)[0]
    assert report.fit_choice.is_consistent
    fits = (report.mean(report.relative_least_squares), report.mean(report.relative_consistent))
    assert report.mean(report.relative_after) <= min(fits) + 1.0
    assert not any("the chosen fit" in w for w in report.warnings)


@pytest.mark.end_to_end
@pytest.mark.skipif(not (SHARED / "exciting_traj_1.csv").exists(), reason="shared Panda data not present")
def test_real_panda_unseen_phase_holds_with_the_defaults_and_validate_scores_the_report_again(tmp_path):
    """Issues 10 and 21: on a phase of the period that neither the fit nor the selection saw, the
    defaults give ≤ 6 % (rigid body alone > 25 %); the reported model is the pair (model, fit) with
    the lowest J of those the cross-validation scored. How little other cut-offs change this is
    measured by bench/identify_settings.py (README), too slow for the tests (three full runs). ``validate``
    scores the report file on other runs (one identification serves both: it takes half a minute)."""
    config = yaml.safe_load((HERE.parent / "configs" / "panda_identify_phase.yaml").read_text())
    for run in config["data"]["runs"]:
        run["file"] = str(SHARED / "exciting_traj_1.csv")
    config["output"] = str(tmp_path / "phase.h5")
    identify = load_problem(write_config(tmp_path, config, "phase.yaml"), IdentifyProblem)
    report = run_identify(identify, tmp_path / "phase.h5").report
    assert report.relative_after.mean() <= 6.0 and report.relative_before.mean() > 25.0
    sel = report.selection
    # exactly the selected model: its CV error is the search's there, its validation error the ladder's end
    kept = sel.searches[sel.chosen]
    assert sel.cv_error == pytest.approx(kept.initial_error if sel.at_start else kept.cv_error, rel=1e-12)
    assert report.ladder[-1][2] == pytest.approx(report.relative_after.mean(), rel=1e-9)
    # the model and fit with the lowest J of every pair scored
    choice = report.fit_choice
    assert choice.objective[choice.model, choice.chosen] == np.nanmin(choice.objective)
    assert set(choice.models[choice.model].terms) == set(sel.terms)
    # friction on every joint
    friction = ("coulomb", "load_coulomb", "viscous", "held", "stribeck")
    assert {t.joint for t in sel.terms if t.effect in friction} == set(range(7))
    # validate: the held-out phase again gives exactly identify's validation errors; the whole run its own
    config["data"]["runs"] = [
        {"file": str(SHARED / "exciting_traj_1.csv"), "crop": [7.8, 13.2]},
        {"file": str(SHARED / "exciting_traj_1.csv")},
    ]
    errors = validate_model(
        tmp_path / "phase.h5", load_problem(write_config(tmp_path, config, "val.yaml"), IdentifyProblem)
    )
    np.testing.assert_allclose(errors[0].relative, report.relative_after, rtol=1e-9)
    assert errors[1].instants > 3 * errors[0].instants and errors[1].relative.mean() < report.relative_before.mean()
    # the report's base parameters stored in another order are taken by name; other ones are refused
    with h5py.File(tmp_path / "phase.h5", "a") as f:
        g = f["identification"]
        names = read_strings(g, "base_parameter_names")
        order = np.random.default_rng(0).permutation(len(names))
        for key in ("base_parameters", "base_parameters_rigid_only"):
            values = g[key][()]
            del g[key]
            g[key] = values[order]
        del g["base_parameter_names"]
        write_strings(g, "base_parameter_names", [names[k] for k in order])
    shuffled = validate_model(tmp_path / "phase.h5", load_problem(tmp_path / "val.yaml", IdentifyProblem))
    np.testing.assert_allclose(shuffled[0].relative, report.relative_after, rtol=1e-9)
    with h5py.File(tmp_path / "phase.h5", "a") as f:
        del f["identification/base_parameter_names"]
        write_strings(f["identification"], "base_parameter_names", ["m_panda_link0"] + names[1:])
    result = runner.invoke(app, ["validate", str(tmp_path / "phase.h5"), str(tmp_path / "val.yaml")])
    assert result.exit_code == 2 and "m_panda_link0" in result.output and "other base parameters" in result.output
    with h5py.File(tmp_path / "phase.h5", "a") as f:
        del f["identification/base_parameter_names"]
        write_strings(f["identification"], "base_parameter_names", [names[k] for k in order])
    result = runner.invoke(
        app, ["validate", str(tmp_path / "phase.h5"), str(tmp_path / "val.yaml")], env={"COLUMNS": "200"}
    )
    assert result.exit_code == 0 and "[7.8, 13.2] s" in result.output
    # a report of other joints, and a file that is not a report: one message each
    config["robot"]["active_joints"] = JOINTS[:6]
    config["data"]["columns"] = {"q": [f"q{k}" for k in range(1, 7)], "tau": [f"tau{k}" for k in range(1, 7)]}
    result = runner.invoke(
        app, ["validate", str(tmp_path / "phase.h5"), str(write_config(tmp_path, config, "other.yaml"))]
    )
    assert result.exit_code == 2 and "other joints" in result.output
    result = runner.invoke(app, ["validate", str(HERE / "panda_capsules.yaml"), str(tmp_path / "val.yaml")])
    assert result.exit_code == 2 and "Traceback" not in result.output


@pytest.mark.end_to_end
@pytest.mark.skipif(not (SHARED / "exciting_traj_1.csv").exists(), reason="shared Panda data not present")
def test_report_has_per_run_validation_errors(tmp_path):
    config = yaml.safe_load((HERE.parent / "configs" / "panda_identify_phase.yaml").read_text())
    runs = config["data"]["runs"]
    for run in runs:
        run["file"] = str(SHARED / "exciting_traj_1.csv")
    runs[2:] = [
        {"file": str(SHARED / "exciting_traj_1.csv"), "crop": crop, "role": "validation"}
        for crop in ([7.8, 10.5], [10.5, 13.2])
    ]  # the unseen phase as two runs
    config["output"] = str(tmp_path / "r.h5")
    result = runner.invoke(app, ["identify", str(write_config(tmp_path, config, "r.yaml"))], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    with h5py.File(tmp_path / "r.h5") as f:
        table = f["identification/validation_runs"][()]
        rms_after = f["identification/rms_after"][()]
    assert [r.decode() for r in table["run"]] == [
        "exciting_traj_1.csv [7.8, 10.5] s",
        "exciting_traj_1.csv [10.5, 13.2] s",
    ]
    # the runs' mean squared errors, weighted by their instants, make up the whole validation's
    total = (table["instants"][:, None] * table["rms_after"] ** 2).sum(axis=0) / table["instants"].sum()
    np.testing.assert_allclose(np.sqrt(total), rms_after, rtol=1e-9)


@pytest.mark.end_to_end
def test_shipped_simulated_runs_give_back_their_undeclared_friction():
    """data/panda_simulated (shipped, no ../shared needed): Coulomb 0.6 Nm and viscous 0.4 Nm·s/rad on
    every joint, undeclared in configs/panda_identify_simulated.yaml."""
    problem = load_problem(CONFIGS / "panda_identify_simulated.yaml", IdentifyProblem)
    report, *_ = run_identification(problem)
    assert {(t.effect, report.joints[t.joint]) for t in report.selection.terms} == {
        (e, j) for e in ("coulomb", "viscous") for j in JOINTS
    }
    for term, _, value, std in report.effect_values():
        assert value == pytest.approx({"coulomb": 0.6, "viscous": 0.4}[term.effect], rel=0.15), term
    assert report.relative_before.mean() > 30.0 and report.relative_after.mean() < 5.0


def test_data_as_labs_record_it_identify_without_conversion(tmp_path, optimized):
    """93.7 Hz runs with no sample_rate set, Unix-time stamps, no header (columns by position) and a
    byte-order mark: the default rate follows the data and the friction is found as in clean data."""
    sim = {"sample_rate": 93.7, "periods": 8, "torque_noise": NOISE, "seed": 2, "effects": {"coulomb": {"*": 0.4}}}
    result = runner.invoke(
        app, ["simulate", str(optimized), str(write_config(tmp_path, sim, "effects.yaml")), "-o", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    for k in (1, 2, 3):
        table = np.loadtxt(tmp_path / f"run_{k}.csv", delimiter=",", skiprows=1)
        table[:, 0] += 1.46e9 + 1000.0 * k
        rows = "\n".join(",".join(f"{v:.12g}" for v in row) for row in table)
        (tmp_path / f"lab_{k}.csv").write_text("\ufeff" + rows + "\n", encoding="utf-8")
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {
            "runs": [{"file": f"lab_{k}.csv", "role": "blocks"} for k in (1, 2, 3)],
            "columns": {"time": 0, "q": list(range(1, 8)), "tau": list(range(8, 15))},
        },
        "identification": {"candidates": ["coulomb"]},
        "output": str(tmp_path / "ident.h5"),
    }
    problem = load_problem(write_config(tmp_path, config, "identify.yaml"), IdentifyProblem)
    assert problem.preprocessing.sample_rate is None
    report = run_identification(problem)[0]
    assert report.cutoff < 0.4 * 93.7 + 1e-9
    found = _found(report)
    assert {j for e, _, j in found if e == "coulomb"} == set(JOINTS)
    for (effect, _, _), (value, std, _) in found.items():
        assert effect != "coulomb" or abs(value - 0.4) <= max(0.1 * 0.4, 3 * std)
    assert np.mean(report.relative_after) < 0.5 * np.mean(report.relative_before)


@pytest.mark.end_to_end
def test_noise_growing_with_the_torque_is_measured_per_joint(tmp_path, optimized):
    """A motor current's noise, 2 % of the torque over a 0.005 N·m floor: identify fits ρ to the fit
    residual within 20 % (median over the joints) and prefers noise growing with the torque."""
    effects = {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}}
    report, *_ = _simulate_and_identify(
        tmp_path, optimized, effects, ["coulomb", "viscous"], torque_noise=0.005, torque_noise_relative=0.02
    )
    rho = np.array([level.relative for level in report.noise_levels])
    assert abs(np.median(rho) / 0.02 - 1) < 0.2, rho
    assert sum(level.preferred == "relative" for level in report.noise_levels) >= 6
