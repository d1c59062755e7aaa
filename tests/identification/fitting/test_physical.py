"""Physically consistent identification: the pseudo-inertia against pinocchio's, the real Panda run
with a written URDF, simulated data with known parameters, and data where plain least squares gives
a negative mass."""

from pathlib import Path

import h5py
import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import CONFIGS, JOINTS, SHARED, panda_runs_config, robot_of, write_config
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem, result_problem
from excite_cli.dynamics.base_parameters import compute_base_parameters
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.fitting.bodies import MARGIN, nearest_physical, pseudo_inertia
from excite_cli.identification.fitting.physical import ConsistentProgram
from excite_cli.identification.pipeline import run_identification
from excite_cli.storage.results import read_alphas
from excite_cli.trajectory.fourier import FourierTrajectory

runner = CliRunner()


def _eigenvalues(phi: np.ndarray) -> np.ndarray:
    """Smallest pseudo-inertia eigenvalue of each body, from pinocchio's PseudoInertia (independent)."""
    return np.array(
        [
            np.linalg.eigvalsh(
                pin.Inertia.FromDynamicParameters(phi[10 * i : 10 * i + 10]).toPseudoInertia().toMatrix()
            )[0]
            for i in range(phi.size // 10)
        ]
    )


def test_pseudo_inertia_matches_pinocchio_and_tells_physical_bodies():
    rng = np.random.default_rng(0)
    for _ in range(5):  # boxes (physical by construction) moved and turned about the body frame
        box = pin.Inertia.FromBox(rng.uniform(0.1, 5.0), *rng.uniform(0.01, 0.5, 3))
        inertia = pin.SE3.Random().act(box)
        phi = inertia.toDynamicParameters()
        assert np.allclose(pseudo_inertia(phi), inertia.toPseudoInertia().toMatrix(), atol=1e-12)
        assert np.linalg.eigvalsh(pseudo_inertia(phi))[0] > 0
    rod = pin.Inertia(1.0, np.zeros(3), np.diag([1.0, 1.0, 3.0]))  # violates I_zz ≤ I_xx + I_yy
    assert np.linalg.eigvalsh(pseudo_inertia(rod.toDynamicParameters()))[0] < 0
    negative = -pin.Inertia.FromBox(1.0, 0.1, 0.2, 0.3).toDynamicParameters()
    assert np.linalg.eigvalsh(pseudo_inertia(negative))[0] < 0


def test_nearest_physical_keeps_physical_bodies_and_mends_the_others_keeping_mass_and_centre():
    box = pin.SE3.Random().act(pin.Inertia.FromBox(2.0, 0.1, 0.2, 0.3)).toDynamicParameters()
    rod = pin.Inertia(1.5, np.array([0.1, -0.2, 0.05]), np.diag([0.01, 0.01, 0.05]))  # I_zz > I_xx + I_yy
    bad = rod.toDynamicParameters()
    out = nearest_physical(np.concatenate([box, bad]))
    assert np.array_equal(out[:10], box)
    assert np.allclose(out[10:14], bad[:4])  # mass and first moment kept
    J = pseudo_inertia(out[10:])
    assert np.linalg.eigvalsh(J)[0] >= MARGIN * 1.5 * 0.1**2  # above the SDP's floor ε_i
    mended = pin.Inertia.FromDynamicParameters(out[10:])
    moments = np.linalg.eigvalsh(mended.inertia)
    assert moments[2] <= moments[0] + moments[1]  # the triangle inequality holds again
    # the nearest: the change is no larger than the violation it removes (I_zz − I_xx − I_yy = 0.03)
    assert np.abs(mended.inertia - rod.inertia).max() <= 0.03 + 1e-9


def test_what_the_data_cannot_place_goes_to_the_payload_not_the_links():
    """Two bodies the data see only summed (one base parameter vector φ₁ + φ₂, well measured) and
    0.5 kg more than the URDF's: held apart as a payload on the second body, it is (almost) all there
    and the links keep the URDF's masses; without a payload the pull toward the URDF puts it on the
    heavier link."""
    first = pin.Inertia.FromBox(2.0, 0.1, 0.2, 0.3).toDynamicParameters()
    second = pin.Inertia.FromBox(0.5, 0.05, 0.05, 0.1).toDynamicParameters()
    extra = pin.Inertia(0.5, np.array([0.0, 0.0, 0.1]), 1e-3 * np.eye(3)).toDynamicParameters()
    K, G = np.hstack([np.eye(10), np.eye(10)]), 1e3 * np.eye(10)
    c = G @ (first + second + extra)
    urdf = np.concatenate([first, second])
    held = ConsistentProgram(G, K, urdf, [], ["link", "flange"], carriers=[1]).solve(G, c, 1, 1e-3)
    # pulled toward none 1000 × more weakly (per unit of its carrier's scale, 4 × the link's): 98.4 %
    np.testing.assert_allclose(held.payloads[0][0], extra[0], rtol=0.02)
    np.testing.assert_allclose(held.standard[0::10], [first[0], second[0] + extra[0]], atol=0.01)
    np.testing.assert_allclose(held.bodies_base, first + second + extra, atol=1e-4)  # the fit itself
    assert held.payload_bodies == ["flange"]
    spread = ConsistentProgram(G, K, urdf, [], ["link", "flange"]).solve(G, c, 1, 1e-3)
    np.testing.assert_allclose(spread.bodies_base, first + second + extra, atol=1e-4)  # the same fit
    assert spread.standard[0] - first[0] > 0.4  # the heavier link takes most of it (its scale is larger)


@pytest.mark.skipif(not (SHARED / "exciting_traj_1.csv").exists(), reason="shared Panda data not present")
@pytest.mark.end_to_end
def test_real_panda_consistent_fit_and_its_urdf(tmp_path):
    config = yaml.safe_load((CONFIGS / "panda_identify.yaml").read_text())
    config["data"]["runs"][0]["file"] = str(SHARED / "exciting_traj_1.csv")
    path = write_config(tmp_path, config, "identify.yaml")
    urdf, report = tmp_path / "panda_identified.urdf", tmp_path / "ident.h5"
    run = runner.invoke(
        app, ["identify", str(path), "--urdf-out", str(urdf), "-o", str(report)], env={"COLUMNS": "200"}
    )
    assert run.exit_code == 0, run.output
    with h5py.File(report) as f:
        g = f["identification"]
        chosen = g.attrs["fit"]  # the URDF is the consistent fit's, whichever the cross-validation chose
        assert g["physically_consistent"][()] == chosen.startswith("consistent")
        standard, base_parameters = g["standard_parameters"][()], g["base_parameters_consistent"][()]
        rotors = dict(zip([j.decode() for j in g["rotor_joints"][()]], g["rotor_inertias"][()]))
        own = dict(zip(rotors, g["rotor_own_columns"][()]))
        consistent, unconstrained = g["relative_consistent"][()].mean(), g["relative_least_squares"][()].mean()
        models, fits = g["models"][()], g["fits"][()]
        winner, model = models[g["models"].attrs["chosen"]], g.attrs["model"]
    # every model scored under every fit; the winning pair has the lowest J, and the fits table is its model's row
    assert models.size == len(set(models["model"])) * fits.size > fits.size
    assert winner["objective"] == models["objective"].min() and winner["fit"].decode() == chosen
    assert winner["model"].decode() == model and model.startswith(("start of '", "end of '"))
    mine = models[models["model"] == winner["model"]]
    np.testing.assert_array_equal(mine["cv_error"], fits["cv_error"])
    assert "Models and fits scored together" in run.output
    assert np.all(_eigenvalues(standard) > 0)
    assert consistent <= unconstrained + 1.0
    # the written URDF, loaded by pinocchio on its own, with the rotors held apart from its bodies
    # (armature I_a q̈ on their joints), against the identified rigid-body torques at the held-out
    # blocks' measured states (blocks 2 and 4 of 4): every joint has a rotor, joints 1-2's in the
    # base parameters, the others' columns of their own
    assert list(rotors) == [f"panda_joint{k}" for k in range(1, 8)] and all(a >= 0 for a in rotors.values())
    assert [j for j, o in own.items() if not o] == ["panda_joint1", "panda_joint2"]
    armature = np.array([rotors[f"panda_joint{k}"] for k in range(1, 8)])
    own_armature = np.array([rotors[j] if o else 0.0 for j, o in own.items()])
    data = np.genfromtxt(SHARED / "exciting_traj_1.csv", delimiter=",", names=True)
    t = data["time"]
    quarter = np.floor(4 * (t - t[0]) / (t[-1] - t[0] + 1e-9)).astype(int)
    rows = np.flatnonzero(quarter % 2 == 1)[::97]
    q = np.column_stack([data[f"q{k}"] for k in range(1, 8)])
    qd = np.column_stack([data[f"dq{k}"] for k in range(1, 8)])
    qdd = np.gradient(qd, t, axis=0)
    written = pin.buildModelFromUrdf(str(urdf))
    written_data = written.createData()
    robot = robot_of(load_problem(path, IdentifyProblem))
    X = compute_base_parameters(robot).composition_matrix
    for r in rows:
        tau = pin.rnea(written, written_data, np.r_[q[r], 0, 0], np.r_[qd[r], 0, 0], np.r_[qdd[r], 0, 0])[:7]
        tau += armature * qdd[r]
        identified = robot.regressor(q[r], qd[r], qdd[r]) @ X @ base_parameters + own_armature * qdd[r]
        assert np.allclose(tau, identified, atol=1e-6)
    assert "from the physically consistent fit" in run.output and "rigid-body torques to" in run.output


def _identify(tmp: Path, runs: list[str]):
    config = panda_runs_config(runs, fit="consistent")
    return run_identification(load_problem(write_config(tmp, config, "identify.yaml"), IdentifyProblem))


def _rigid_runs(tmp: Path, optimized: Path, truth: np.ndarray, periods: int, seed: int, prefix: str) -> list[str]:
    """One CSV per trajectory of ``optimized``: ``periods`` periods at 500 Hz of the rigid-body torques of
    the standard parameters ``truth`` (p,) plus 0.05 Nm of white noise; their file names in ``tmp``."""
    problem = result_problem(optimized)
    robot = robot_of(problem)
    trajectory = FourierTrajectory(problem.trajectory.harmonics, problem.trajectory.base_frequency)
    rng = np.random.default_rng(seed)
    files = []
    for k, alpha in read_alphas(optimized):
        time = np.arange(int(periods * trajectory.period * 500) + 1) / 500.0
        q, qd, qdd = trajectory.basis(time).evaluate(alpha)
        tau = np.array([robot.regressor(*x) @ truth for x in zip(q, qd, qdd)]) + rng.normal(0, 0.05, q.shape)
        header = ",".join(["time"] + [f"q_{j}" for j in JOINTS] + [f"tau_{j}" for j in JOINTS])
        files.append(f"{prefix}_{k}.csv")
        np.savetxt(tmp / files[-1], np.column_stack([time, q, tau]), delimiter=",", header=header, comments="")
    return files


@pytest.mark.end_to_end
def test_simulated_data_consistent_fit_recovers_the_base_parameters(tmp_path, optimized):  # noqa: F811
    sim = {
        "sample_rate": 500,
        "periods": 8,
        "timestamp_jitter": 0.1,
        "torque_noise": 0.05,
        "seed": 4,
        "effects": {"coulomb": {"*": 0.6}, "viscous": {"*": 0.4}},
    }
    result = runner.invoke(
        app, ["simulate", str(optimized), str(write_config(tmp_path, sim, "effects.yaml")), "-o", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    report, robot, base, _ = _identify(tmp_path, [f"run_{k}.csv" for k in (1, 2, 3)])
    truth = base.from_standard(robot.urdf_parameters())
    estimate, std = report.consistent.base, report.selection.fit.std[: base.count]
    assert np.linalg.norm(estimate - truth) < 0.01 * np.linalg.norm(truth)
    assert np.mean(np.abs(estimate - truth) <= 3 * std) > 0.95
    assert np.all(_eigenvalues(report.consistent.standard) > 0)


@pytest.mark.end_to_end
def test_negative_mass_data_stays_physical_with_the_consistent_fit(tmp_path, optimized):  # noqa: F811
    """Torques of a model whose hand body (link 7 with the hand merged) has all parameters negated:
    plain least squares says its mass is negative, the consistent fit keeps every body physical."""
    robot = robot_of(result_problem(optimized))
    truth = robot.urdf_parameters()
    truth[60:70] *= -1.0
    report, *_ = _identify(tmp_path, _rigid_runs(tmp_path, optimized, truth, 4, 0, "neg"))
    plain, consistent = report.consistent.unconstrained, report.consistent.standard
    assert plain[60] < 0  # plain least squares: a negative mass of the hand body
    assert np.all(consistent[0::10] > 0) and np.all(_eigenvalues(consistent) > 0)


@pytest.mark.end_to_end
def test_rotors_that_regroup_with_the_links_stay_out_of_the_bodies(tmp_path, optimized):  # noqa: F811
    """A simulated Panda whose joints 1 and 2 have rotors of 0.3 kg·m² (an armature that regroups with
    link inertias in the base parameters, so least squares cannot tell them apart): the consistent fit
    holds them apart, the rotors within 5 % and every body's mass within 5 % of the URDF (the truth),
    and it predicts the held-out blocks about as well as least squares (without the rotors, link 3's
    mass came out 39 % low)."""
    sim = {
        "sample_rate": 250,
        "periods": 2,
        "torque_noise": 0.05,
        "seed": 4,
        "effects": {
            "coulomb": {"*": 0.6},
            "viscous": {"*": 0.4},
            "armature": {"panda_joint1": 0.3, "panda_joint2": 0.3},
        },
    }
    result = runner.invoke(
        app, ["simulate", str(optimized), str(write_config(tmp_path, sim, "effects.yaml")), "-o", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    report, robot, base, _ = _identify(tmp_path, [f"run_{k}.csv" for k in (1, 2, 3)])
    fit = report.consistent
    assert fit.rotor_joints == JOINTS and list(fit.own_columns) == [False] * 2 + [True] * 5
    np.testing.assert_allclose(fit.rotors[:2], [0.3, 0.3], rtol=0.05)
    assert np.all(fit.rotors[2:] <= 2e-3)  # none in the data
    urdf = robot.urdf_parameters()
    np.testing.assert_allclose(fit.standard[0::10], urdf[0::10], rtol=0.05)
    assert report.relative_consistent.mean() <= 1.3 * report.relative_least_squares.mean()


@pytest.mark.end_to_end
def test_an_undeclared_payload_on_the_flange_is_a_body_of_its_own_and_the_links_keep_their_masses(
    tmp_path,
    optimized,  # noqa: F811
):
    """Torques of the Panda carrying 1 kg 10 cm beyond the flange, not declared: the payload regroups
    with the links below it, so the data cannot say which body carries it; the consistent fit holds it
    apart on the last body (pulled toward none far more weakly than the links toward the URDF), so
    links 1-6 keep the URDF's masses (the truth) and the last body comes out with the payload's."""
    robot = robot_of(result_problem(optimized))
    urdf = robot.urdf_parameters()
    payload = pin.Inertia(1.0, np.array([0.0, 0.0, 0.1]), np.diag([2e-3, 2e-3, 1e-3])).toDynamicParameters()
    truth = urdf.copy()
    truth[-10:] += payload
    report, *_ = _identify(tmp_path, _rigid_runs(tmp_path, optimized, truth, 2, 1, "load"))
    fit = report.consistent
    assert fit.payload_bodies == [robot.body_names[-1]]
    np.testing.assert_allclose(fit.standard[0:60:10], urdf[0:60:10], rtol=0.01)  # links 1-6
    np.testing.assert_allclose(fit.standard[60], truth[60], rtol=0.02)  # the last body with the payload
    np.testing.assert_allclose(fit.payloads[0, :4], payload[:4], rtol=0.05, atol=0.005)  # mass and first moment
