"""Models that hold on runs the fit never saw (simulated Panda data with known parameters): recording
folds drop an effect present in one fit run only; on poorly exciting fit runs the fit chosen by the
cross-validation is as good on a validation run elsewhere as the better of least squares and the
physically consistent fit; a position effect fitted on a narrower q range than the validation run's
is held at the ends of that range."""

from pathlib import Path

import numpy as np
import pytest
from conftest import JOINTS, NOISE, robot_of, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem, result_problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.fitting.least_squares import torque_errors
from excite_cli.identification.pipeline import run_identification
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.identification.validate import validate_model
from excite_cli.storage.results import read_alphas
from excite_cli.trajectory.fourier import FourierTrajectory
from excite_cli.workflows.simulate import simulate_runs

COLUMNS = {"q": [f"q_{j}" for j in JOINTS], "tau": [f"tau_{j}" for j in JOINTS]}
ROBOT = {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS}


runner = CliRunner()


def _identify(tmp: Path, runs: list[dict], name: str, **identification):
    config = {"robot": ROBOT, "data": {"runs": runs, "columns": COLUMNS}, "identification": identification}
    return run_identification(load_problem(write_config(tmp, config, f"{name}.yaml"), IdentifyProblem))[0]


def _mean(report) -> float:
    return float(report.relative_after.mean())


@pytest.mark.end_to_end
def test_an_effect_of_one_fit_run_is_dropped_by_recording_folds(tmp_path, optimized):  # noqa: F811
    """Coulomb friction 0.4 Nm on every joint in every run; viscous friction 0.6 Nm·s/rad on joint 5
    only in the first fit run (a pattern of one run). Fit on three recordings, validate on a fourth."""
    coulomb = {"coulomb": {"*": 0.4}}
    for prefix, effects in (("a", {**coulomb, "viscous": {"panda_joint5": 0.6}}), ("b", coulomb)):
        sim = SimulationConfig(sample_rate=500, periods=3, torque_noise=NOISE, seed=len(prefix), effects=effects)
        simulate_runs(optimized, sim, tmp_path, prefix)
    runs = [{"file": f, "role": "fit"} for f in ("a_1.csv", "b_2.csv", "b_3.csv")]
    runs.append({"file": "b_1.csv", "role": "validation"})
    default = _identify(tmp_path, runs, "default")
    assert default.selection.folds_by == "recording"
    found = {(t.effect, JOINTS[t.joint]) for t in default.selection.terms}
    assert found == {("coulomb", j) for j in JOINTS}, found
    true = _identify(tmp_path, runs, "true", candidates=[], declared_effects={"*": ["coulomb"]}, fit="least_squares")
    assert _mean(default) <= 1.10 * _mean(true)
    textbook = _identify(tmp_path, runs, "textbook", candidates=[], declared_effects={"*": ["coulomb", "viscous"]})
    assert _mean(default) <= _mean(textbook)
    blocks = _identify(tmp_path, runs, "blocks", folds_by="time_block")
    assert ("viscous", 4) in {(t.effect, t.joint) for t in blocks.selection.terms}  # fitted inside run a
    print(
        f"validation error: recording folds {_mean(default):.2f} %, time blocks {_mean(blocks):.2f} %, "
        f"true model {_mean(true):.2f} %, Coulomb + viscous everywhere {_mean(textbook):.2f} % "
        f"({textbook.fit_choice.name})"
    )


def _write_run(path: Path, time, q, tau) -> str:
    header = ",".join(["time"] + COLUMNS["q"] + COLUMNS["tau"])
    np.savetxt(path, np.column_stack([time, q, tau]), delimiter=",", header=header, comments="")
    return path.name


@pytest.mark.end_to_end
@pytest.mark.parametrize("amplitude", [0.1])
def test_poorly_exciting_fit_runs_get_the_fit_that_transfers(tmp_path, optimized, amplitude):  # noqa: F811
    """Fit runs: two optimized motions shrunk to ``amplitude`` about their mean posture, one period
    each; validation: a third motion at full amplitude. The robot's bodies are the URDF's scaled by
    0.85–1.15 (a CAD model near the truth), Coulomb friction 0.3 Nm, noise 0.05 Nm. The default is as
    good as the better fit, and keeps the true effects where the least-squares search adds spurious ones."""
    problem = result_problem(optimized)
    robot = robot_of(problem)
    rng = np.random.default_rng(1)
    truth = robot.urdf_parameters() * np.repeat(rng.uniform(0.85, 1.15, robot.urdf_parameters().size // 10), 10)
    trajectory = FourierTrajectory(problem.trajectory.harmonics, problem.trajectory.base_frequency)
    time = np.arange(int(trajectory.period * 500) + 1) / 500.0
    runs = []
    for k, alpha in read_alphas(optimized):
        q, qd, qdd = trajectory.basis(time).evaluate(alpha)
        scale = 1.0 if k == 3 else amplitude
        q, qd, qdd = q.mean(axis=0) + scale * (q - q.mean(axis=0)), scale * qd, scale * qdd
        tau = np.array([robot.regressor(*x) @ truth for x in zip(q, qd, qdd)])
        tau += 0.3 * np.tanh(qd / 0.01) + rng.normal(0.0, NOISE, q.shape)
        runs.append(
            {"file": _write_run(tmp_path / f"run_{k}.csv", time, q, tau), "role": "fit" if k < 3 else "validation"}
        )
    default = _identify(tmp_path, runs, "default")
    choice = default.fit_choice
    assert choice.names[0] == "least squares" and len(choice.names) > 2 and np.all(np.isfinite(choice.cv_error))
    plain = float(default.relative_least_squares.mean())
    consistent = float(default.relative_consistent.mean())
    assert abs(plain - consistent) > 0.2 * min(plain, consistent)  # the choice matters here
    assert _mean(default) <= 1.05 * min(plain, consistent)
    measured = default.validation.tau.reshape(-1, len(JOINTS))
    chosen = torque_errors(measured, default.predicted_after)[2].mean()
    assert chosen == pytest.approx(_mean(default))
    # the effects are chosen with the fit: the true model's, none that only least squares needed
    assert {(t.effect, t.joint) for t in default.selection.terms} == {("coulomb", j) for j in range(len(JOINTS))}
    textbook = _identify(tmp_path, runs, "textbook", candidates=[], declared_effects={"*": ["coulomb", "viscous"]})
    assert _mean(default) <= _mean(textbook)
    print(
        f"chosen {choice.labels[choice.model]} ({len(default.selection.terms)} effects), {choice.name}: "
        f"{_mean(default):.2f} %; least squares {plain:.2f} %, consistent {consistent:.2f} %; "
        f"CV {dict(zip(choice.names, np.round(choice.cv_error, 2)))}; "
        f"Coulomb + viscous declared, {textbook.fit_choice.name}: {_mean(textbook):.2f} %"
    )


@pytest.mark.end_to_end
def test_a_position_effect_fitted_on_a_narrower_range_is_held_at_its_ends(tmp_path, optimized):  # noqa: F811
    """A cable-like torque 0.3 tanh((q₆ − q̄₆)/w) Nm on joint 6 that saturates outside the fit runs'
    q range: fit runs are two optimized motions at half amplitude about their mean posture,
    validation a third at full amplitude. With the position effects as candidates, the guard (the
    default) holds the fitted term at the ends of the fit range instead of extrapolating it."""
    problem = result_problem(optimized)
    robot = robot_of(problem)
    trajectory = FourierTrajectory(problem.trajectory.harmonics, problem.trajectory.base_frequency)
    time = np.arange(2 * int(trajectory.period * 500) + 1) / 500.0
    rng = np.random.default_rng(2)
    motions = {k: trajectory.basis(time).evaluate(alpha) for k, alpha in read_alphas(optimized)}
    centre = np.mean([q.mean(axis=0) for q, _, _ in motions.values()], axis=0)
    width = 0.5 * np.abs(motions[3][0][:, 5] - centre[5]).max() * 0.6
    runs = []
    for k, (q, qd, qdd) in motions.items():
        scale = 1.0 if k == 3 else 0.5
        q, qd, qdd = centre + scale * (q - centre), scale * qd, scale * qdd
        tau = np.array([robot.regressor(*x) @ robot.urdf_parameters() for x in zip(q, qd, qdd)])
        tau += 0.3 * np.tanh(qd / 0.01) + rng.normal(0.0, NOISE, q.shape)
        tau[:, 5] += 0.3 * np.tanh((q[:, 5] - centre[5]) / width)
        runs.append(
            {"file": _write_run(tmp_path / f"run_{k}.csv", time, q, tau), "role": "fit" if k < 3 else "validation"}
        )
    position = ["coulomb", "viscous", "spring", "gravity_compensator", "position_2"]
    guarded = _identify(tmp_path, runs, "guarded", candidates=position, fit="least_squares")
    free = _identify(tmp_path, runs, "free", candidates=position, fit="least_squares", position_guard=False)
    plain = _identify(tmp_path, runs, "plain", candidates=["coulomb", "viscous"], fit="least_squares")
    # the range the fit saw: the fit runs' q (filtered, so within a few mrad), narrower than the validation's
    fit_q = np.vstack([centre + 0.5 * (motions[k][0] - centre) for k in (1, 2)])
    np.testing.assert_allclose(guarded.q_range, np.column_stack([fit_q.min(0), fit_q.max(0)]), atol=5e-3)
    assert free.q_range is None
    outside = np.mean((motions[3][0][:, 5] < guarded.q_range[5, 0]) | (motions[3][0][:, 5] > guarded.q_range[5, 1]))
    print(f"validation instants outside the fit range of joint 6: {100 * outside:.0f} %")
    assert outside > 0.2
    # the same selection and fit (the fit data lie inside the range), a position effect on joint 6
    assert guarded.selection.terms == free.selection.terms
    assert any(t.kind.position and t.joint == 5 for t in guarded.selection.terms)
    assert guarded.relative_after[5] < 0.6 * free.relative_after[5]
    assert guarded.relative_after.mean() < free.relative_after.mean() < plain.relative_after.mean()
    # validate holds the terms to the same range (the report stores it)
    config = write_config(
        tmp_path,
        {
            "robot": ROBOT,
            "data": {"runs": runs, "columns": COLUMNS},
            "identification": {"candidates": position, "fit": "least_squares"},
        },
        "cli.yaml",
    )
    result = runner.invoke(app, ["identify", str(config), "-o", str(tmp_path / "guarded.h5")])
    assert result.exit_code == 0 and "held at their value at the ends of the fit data's q range" in result.output
    errors = validate_model(tmp_path / "guarded.h5", load_problem(config, IdentifyProblem))
    np.testing.assert_allclose(errors[2].relative, guarded.relative_after, rtol=1e-9)
    print(
        "joint 6 validation error: "
        + ", ".join(
            f"{name} {r.relative_after[5]:.2f} % (mean {r.relative_after.mean():.2f} %)"
            for name, r in (("guarded", guarded), ("unguarded", free), ("no position effects", plain))
        )
    )
