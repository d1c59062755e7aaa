"""An identify report's chosen effects as the next design's columns (``effects.model``)."""

from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import CONFIGS
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.errors import ExciteError
from excite_cli.h5 import read_strings
from excite_cli.stored.design_model import (
    MEASURED_FLOOR,
    MeasuredPrior,
    measured_prior_of,
    report_model,
    with_report_model,
)
from excite_cli.stored.inputs import read_inputs
from excite_cli.stored.prior import prior_rows, read_prior_file
from excite_cli.stored.report import read_identify_report, read_report


def test_the_reports_friction_becomes_the_designs_columns(report_file, simulated_identification):
    """The shipped simulated runs hold Coulomb and viscous friction on every joint, which identify finds
    (test_report_file); a design with the report as its model gets exactly those columns."""
    _, report, robot, *_ = simulated_identification
    model = report_model(read_identify_report(report_file, "effects.model"))
    assert {j: sorted(kinds) for j, kinds in model.joints.items()} == {
        j: ["coulomb", "viscous"] for j in robot.joint_names
    }
    assert model.motors == [] and model.left_out == [] and model.coulomb_velocity == 0.01
    problem = load_problem(CONFIGS / "smoke.yaml")
    problem.effects.model = str(report_file)
    excitation = build_excitation(problem)
    assert set(excitation.effect_names) == {f"{c}_{j}" for j in robot.joint_names for c in ("Fc", "Fv")}


def test_a_report_with_a_coupled_motor_and_a_shaped_effect(report_file, tmp_path):
    path = tmp_path / "edited.h5"
    path.write_bytes(report_file.read_bytes())
    with h5py.File(path, "a") as f:
        rows, coupling = f["identification/effects"][()], f["identification/effect_coupling"][()]
        rows["effect"][0], rows["effect"][1] = "stribeck", "motor"
        coupling[1, 5:7] = [1.0, 1.0]
        del f["identification/effects"], f["identification/effect_coupling"]
        f["identification/effects"], f["identification/effect_coupling"] = rows, coupling
    model = report_model(read_identify_report(path, "effects.model"))
    assert model.motors == [(["panda_joint6", "panda_joint7"], [1.0, 1.0])]
    assert model.left_out == [f"stribeck ({rows['joint'][0].decode()})"]


def test_a_file_that_is_not_a_report_or_of_other_joints_is_refused_naming_the_field(report_file, optimized):
    problem = load_problem(CONFIGS / "smoke.yaml")
    problem.effects.model = str(optimized)
    with pytest.raises(ExciteError, match=r"effects\.model.*is not an identify report"):
        read_inputs(problem.effects.model, None, problem.folder)
    report = read_identify_report(report_file, "effects.model")
    with pytest.raises(ExciteError, match=r"effects\.model.*'panda_joint\d', which is not an active joint"):
        with_report_model(problem.effects, report, report_file, ["shoulder_pan_joint"])


def test_optimize_opens_a_report_named_as_model_and_prior_once(report_file, tmp_path, monkeypatch):
    """`excite optimize CONFIG --model REPORT.h5 --prior REPORT.h5`: the design's model, the weighing of
    its rows and the rows themselves come from one opening of the file."""
    opened, real = [], h5py.File

    def counted(name, *args, **kwargs):
        opened.append(Path(name).resolve() if isinstance(name, (str, Path)) else name)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(h5py, "File", counted)
    both = ["--model", str(report_file), "--prior", str(report_file)]
    run = CliRunner().invoke(
        app, ["optimize", str(CONFIGS / "smoke.yaml"), *both, "-o", str(tmp_path / "o.h5"), "-k", "1"]
    )
    assert run.exit_code == 0, run.output
    assert opened.count(report_file.resolve()) == 1 and len(opened) > 1  # the result was written too


def test_optimize_with_the_report_as_model_designs_for_its_friction(report_file, tmp_path, monkeypatch):
    """`excite optimize CONFIG --model REPORT.h5`, the path relative to where the user stands."""
    monkeypatch.chdir(report_file.parent)
    out = tmp_path / "next.h5"
    run = CliRunner().invoke(
        app, ["optimize", str(CONFIGS / "smoke.yaml"), "--model", report_file.name, "-o", str(out), "-k", "1"]
    )
    assert run.exit_code == 0, run.output
    with h5py.File(out) as f:
        names = read_strings(f["robot"], "effect_names")
        assert (
            len(names) == 14 and f["iterations/1/regressor"].shape[1] == f["robot/base_parameter_names"].shape[0] + 14
        )


def test_a_second_of_recording_weighs_as_a_second_on_the_cost_grid():
    """The same motion sampled 7 times finer than the cost grid: scaled by √(1/(cost_period·rate)) its
    information matrix equals the cost grid's (both are Riemann sums of ∫ YᵀY dt per second)."""
    excitation = build_excitation(load_problem(CONFIGS / "smoke.yaml"))
    alpha = excitation.random_start(np.random.default_rng(3))
    period = excitation.spec.trajectory.cost_period
    duration = excitation.spec.trajectory.duration
    fine = excitation.trajectory.basis(np.arange(0.0, duration, period / 7.0))
    Y = excitation.robot.regressor_stack(*fine.evaluate(alpha))[:, excitation.base.independent]
    prior = MeasuredPrior(excitation.robot.joint_names, np.ones(excitation.robot.n_joints), 7.0 / period)
    scaled = Y * prior.time_scale(period)
    own = excitation.criterion(weighed=False).regressor(alpha)
    gram_fine, gram_cost = scaled.T @ scaled, own.T @ own
    assert np.linalg.norm(gram_fine - gram_cost) <= 0.05 * np.linalg.norm(gram_cost)


def test_a_joints_rows_weigh_by_its_unexplained_torque():
    prior = MeasuredPrior(["a", "b", "c"], np.array([0.1, 0.4, 0.2]), 200.0)
    np.testing.assert_allclose(prior.weights(), 0.2 / np.array([0.1, 0.4, 0.2]))  # σ̄ = (0.1·0.4·0.2)^⅓ = 0.2


def test_a_reports_rows_weighed_by_its_measured_noise_have_equal_noise():
    """Residuals drawn with noise a² + (ρτ)² growing with the torque (a motor current's, 2 % over a
    0.01 Nm floor) times the rows' weights: the same variance σ̄² at small and at large torques (within
    5 % over 20000 draws per bin), as weighted least squares needs; σ_j alone leaves them 10× apart."""
    rng = np.random.default_rng(0)
    level = np.array([[0.01, 0.02, 0.01], [0.01, 0.02, 0.01]])
    prior = MeasuredPrior(["a", "b"], np.array([0.05, 0.05]), 200.0, level)
    tau = np.repeat([0.0, 5.0], 40000)  # two joints, instants one after another: 20000 draws per bin and joint
    residual = rng.normal(0.0, 1.0, tau.size) * np.sqrt(0.01**2 + (0.02 * tau) ** 2)
    small = np.var(residual[:40000] * prior.row_weights(tau)[:40000])
    large = np.var(residual[40000:] * prior.row_weights(tau)[40000:])
    assert abs(small / prior.noise**2 - 1) < 0.05 and abs(large / prior.noise**2 - 1) < 0.05
    plain = np.tile(prior.weights(), tau.size // 2)
    assert np.var(residual[40000:] * plain[40000:]) > 10 * np.var(residual[:40000] * plain[:40000])


def test_optimize_with_the_report_as_prior_weighs_both_the_prior_and_its_own_rows(report_file, tmp_path):
    """`excite optimize CONFIG --prior REPORT.h5`: the report's rows enter weighted by σ̄/σ_j and the time
    rule, and the new trajectory's rows by the noise the report fitted, σ̄/√(a_j² + ρ_j² τ²) at the
    report's rate (the noise the next run will see; a_j the fitted a's upper bound), and optimize says so."""
    out = tmp_path / "next.h5"
    run = CliRunner().invoke(
        app, ["optimize", str(CONFIGS / "smoke.yaml"), "--prior", str(report_file), "-o", str(out), "-k", "1"]
    )
    assert run.exit_code == 0, run.output
    assert "What the new trajectories determine better" in run.output
    assert "designed for the rows weighed by the noise the identify report measured" in " ".join(run.output.split())
    measured = measured_prior_of(read_report(report_file, "sequence.prior"), report_file)
    assert measured is not None and measured.rate > 0
    with h5py.File(report_file) as f:
        table = f["identification/noise_level"]
        gain = float(table.attrs["noise_gain"])
        level = np.column_stack([table["absolute"], table["relative"], table["absolute_upper"]]) * np.sqrt(gain)
    assert 0 < gain < 1  # the low-pass keeps a share of white noise
    problem = load_problem(CONFIGS / "smoke.yaml")
    excitation = build_excitation(problem)
    with h5py.File(out) as f:
        alpha, stored = f["iterations/1/alpha"][()], f["iterations/1/regressor"][()]
    plain = excitation.criterion(weighed=False).regressor(alpha)
    np.testing.assert_array_equal(stored, plain)  # the file holds the rows as they are (Table I's)
    problem.sequence.prior = str(report_file)
    own = build_excitation(problem).criterion().regressor(alpha)  # as the design weighs them
    robot = excitation.robot
    tau = np.array([robot.torques(*x) for x in zip(*excitation.cost_basis.evaluate(alpha))]).ravel()  # RNEA
    floor = np.maximum(level[:, 2], MEASURED_FLOOR * measured.floored)
    sigma = np.tile(floor, tau.size // 7)
    rho = np.tile(level[:, 1], tau.size // 7)
    weights = measured.noise / np.sqrt(sigma**2 + (rho * tau) ** 2)
    np.testing.assert_allclose(own, plain * weights[:, None], rtol=1e-9, atol=1e-12)


def test_the_reports_rows_hold_its_effects_as_the_fit_saw_them(simulated_identification):
    """The effect columns beside the base regressor are the chosen model's own: with the fitted
    coefficients, [Y_B | Y_E] reproduces the model's prediction on the validation rows (Coulomb and
    viscous friction, all of which a design holds, in the fit's order)."""
    from excite_cli.identification.fitting.least_squares import predict

    _, report, robot, _, rows = simulated_identification
    fit = report.selection.fit
    assert rows.effect_names == [
        f"{'Fc' if t.effect == 'coulomb' else 'Fv'}_{robot.joint_names[t.joint]}" for t in report.selection.terms
    ]
    stacked = np.hstack([rows.regressor[1], rows.effects[1]])
    predicted = predict(report.validation, fit.x, report.selection.terms).ravel()
    np.testing.assert_allclose(stacked @ fit.x, predicted, atol=1e-9)
    np.testing.assert_allclose(rows.predicted[1], report.predicted_after.ravel(), atol=1e-9)  # the reported model's


def test_one_report_is_the_model_and_the_prior_data(report_file, tmp_path):
    """`excite optimize CONFIG --model REPORT.h5 --prior REPORT.h5`: C₀ holds the report's friction
    columns beside its base columns, those columns weighed as the base columns are; a design effect
    the report did not identify is refused naming it."""
    problem = load_problem(CONFIGS / "smoke.yaml")
    problem.effects.model = problem.sequence.prior = str(report_file)
    excitation = build_excitation(problem)
    prior = prior_rows(read_prior_file(report_file), excitation.base, excitation.effect_names, excitation.measured, 0.2)
    with h5py.File(report_file) as f:
        held = [str(name) for name in f["effect_regressor"].attrs["names"]]
        raw = f["effect_regressor"][()][:, [held.index(name) for name in excitation.effect_names]]
        predicted = f["predicted_torque"][()]
    measured = excitation.measured
    weights = measured.row_weights(predicted) * measured.time_scale(0.2)
    np.testing.assert_allclose(prior[:, excitation.base.count :], raw * weights[:, None], rtol=1e-12)
    assert np.abs(prior[:, excitation.base.count :]).max(axis=0).min() > 0.0
    out = tmp_path / "next.h5"
    cli = ["optimize", str(CONFIGS / "smoke.yaml"), "--model", str(report_file), "--prior", str(report_file)]
    run = CliRunner().invoke(app, [*cli, "-o", str(out), "-k", "1"])
    assert run.exit_code == 0, run.output
    problem.effects.joints = {"panda_joint2": ["offset"]}
    extra = build_excitation(problem)
    with pytest.raises(ExciteError, match=r"sequence\.prior.*not this design's tau0_panda_joint2"):
        prior_rows(read_prior_file(report_file), extra.base, extra.effect_names, extra.measured, 0.2)


def test_a_report_whose_rows_do_not_match_is_refused_in_one_line(report_file, tmp_path):
    """A hand-edited report: /effect_regressor with fewer rows than /regressor, then /regressor cut
    to a row count that is no whole number of instants; each is refused naming the prior, not a
    numpy error."""
    import shutil

    problem = load_problem(CONFIGS / "smoke.yaml")
    problem.effects.model = problem.sequence.prior = str(report_file)
    excitation = build_excitation(problem)
    edited = tmp_path / "edited.h5"
    shutil.copy(report_file, edited)
    with h5py.File(edited, "a") as f:
        names = f["effect_regressor"].attrs["names"]
        short = f["effect_regressor"][()][:-7]
        del f["effect_regressor"]
        f.create_dataset("effect_regressor", data=short).attrs["names"] = names
    args = (excitation.base, excitation.effect_names, excitation.measured, 0.2)
    with pytest.raises(ExciteError, match=r"sequence\.prior.*effect_regressor of shape"):
        prior_rows(read_prior_file(edited), *args)
    with h5py.File(edited, "a") as f:
        rows = f["regressor"][()][:-3]
        del f["regressor"]
        f["regressor"] = rows
    with pytest.raises(ExciteError, match=r"sequence\.prior.*not a whole number of instants"):
        prior_rows(read_prior_file(edited), excitation.base, (), excitation.measured, 0.2)


def _damaged(report_file, tmp_path, edit):
    """A copy of the report with ``edit(h5py.File)`` applied."""
    path = tmp_path / "damaged.h5"
    path.write_bytes(report_file.read_bytes())
    with h5py.File(path, "a") as f:
        edit(f)
    return path


def _replace(f, name, value):
    del f[name]
    f[name] = value


def _noise(f, column, value):
    table = f["identification/noise_level"]
    rows = table[()]
    rows[column][0] = value
    table[...] = rows


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda f: _replace(f, "identification/rms_after", np.zeros(7)), "rms_after must hold"),
        (lambda f: _replace(f, "identification/rms_after", np.full(7, np.nan)), "rms_after must hold"),
        (lambda f: _replace(f, "identification/rms_after", np.ones(3)), "rms_after must hold"),
        (lambda f: _replace(f, "identification/rms_after", np.r_[1e300, np.ones(6)]), "an error of 1e.300 Nm"),
        (lambda f: f["regressor"].attrs.__setitem__("sample_rate_Hz", 1e300), "sample_rate_Hz is 1e.300"),
        (lambda f: f["regressor"].attrs.__setitem__("sample_rate_Hz", 0.0), "sample_rate_Hz is 0"),
        (lambda f: f["identification/rms_after"].parent.pop("rms_after"), "report of an earlier excite"),
        (lambda f: f["regressor"].attrs.__delitem__("sample_rate_Hz"), "report of an earlier excite"),
        (lambda f: _noise(f, "relative", -0.01), "noise_level must give each joint a and its bound in 0 to 1e.06 Nm"),
        (lambda f: _noise(f, "absolute", np.inf), "noise_level must give each joint a and its bound in 0 to 1e.06 Nm"),
        (lambda f: f["identification/noise_level"].attrs.__setitem__("noise_gain", 0.0), "noise_gain is 0"),
        (lambda f: _replace(f, "identification/noise_level", np.ones(7)), "needs a row per joint"),
    ],
)
def test_a_damaged_report_as_prior_is_refused_in_one_line(report_file, tmp_path, edit, message):
    """What a report's weighing divides by: errors of its joints and its rate (issue 62: rms_after all
    zero ended in LinAlgError, a rate of 0 in ZeroDivisionError, a report of the previous release's
    format was used unweighted in silence)."""
    with pytest.raises(ExciteError, match=message) as error:
        damaged = _damaged(report_file, tmp_path, edit)
        measured_prior_of(read_report(damaged, "sequence.prior"), damaged)
    assert error.value.field == "sequence.prior"


@pytest.mark.parametrize("torque", [np.full(4, 1.0), np.array([np.nan])])
def test_a_reports_damaged_predicted_torques_are_refused_in_one_line(report_file, tmp_path, torque):
    """/predicted_torque with a row count other than /regressor's, or with NaN: refused naming it, not
    a broadcasting error or rows weighed by NaN."""
    problem = load_problem(CONFIGS / "smoke.yaml")
    problem.sequence.prior = str(report_file)
    excitation = build_excitation(problem)

    def edit(f):
        rows = f["predicted_torque"].shape[0]
        _replace(f, "predicted_torque", torque if torque.size > 1 else np.r_[torque, np.ones(rows - 1)])

    damaged = _damaged(report_file, tmp_path, edit)
    with pytest.raises(ExciteError, match="predicted_torque must hold a finite torque") as error:
        prior_rows(read_prior_file(damaged), excitation.base, (), excitation.measured, 0.2)
    assert error.value.field == "sequence.prior"


def test_a_damaged_report_as_model_is_refused_in_one_line(report_file, tmp_path):
    """An effects table without its effect field, a Coulomb velocity scale of NaN (issue 62: a ValueError
    from numpy; the Coulomb columns dropped with a false warning)."""
    with h5py.File(report_file) as f:
        rows = f["identification/effects"][()]
    renamed = rows.astype([("kind" if n == "effect" else n, rows.dtype[n]) for n in rows.dtype.names])
    no_field = _damaged(report_file, tmp_path, lambda f: _replace(f, "identification/effects", renamed))
    with pytest.raises(ExciteError, match="has no field 'effect'"):
        report_model(read_identify_report(no_field, "effects.model"))
    nan = _damaged(
        report_file, tmp_path, lambda f: f["identification"].attrs.__setitem__("coulomb_velocity_rad_s", np.nan)
    )
    with pytest.raises(ExciteError, match="coulomb_velocity_rad_s is nan") as error:
        report_model(read_identify_report(nan, "effects.model"))
    assert error.value.field == "effects.model"
