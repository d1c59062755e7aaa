"""Torque limits (issue 19): |τ_i| ≤ τ_max,i on the constraint grid, τ the URDF model's RNEA, with
the Jacobian of pinocchio's RNEA derivatives; checked against central differences and against
pinocchio's RNEA of the exported motion, computed here from the URDF independently."""

import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import CONFIGS, assert_refused, constraint_jacobian_error, exported_motion, small
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.constraints.torque_limits import TorqueLimits
from excite_cli.dynamics.robot import example_robot_data_root
from excite_cli.optimization.excitation import build_excitation

runner = CliRunner()
PANDA_JOINTS = [f"panda_joint{k}" for k in range(1, 8)]


@pytest.mark.parametrize("problem", ["panda_problem", "ur5_problem", "g1_problem"])
def test_the_torque_limit_jacobian_matches_central_differences(request, problem):
    problem = small(request.getfixturevalue(problem), harmonics=3)
    problem.trajectory.constraint_period = 0.2  # 41 instants: the differences stay quick
    problem.limits.torque = 0.5
    excitation = build_excitation(problem)
    constraint = next(c for c in excitation.constraints if isinstance(c, TorqueLimits))
    alpha = excitation.limits.random_start(excitation.trajectory.n_coefficients, np.random.default_rng(3), 0.8)
    g = constraint.evaluate(alpha)[0]
    assert g.shape == (2 * excitation.robot.n_joints,)
    assert constraint_jacobian_error(constraint, alpha) <= 1e-6


def _panda_torques(csv) -> tuple[np.ndarray, np.ndarray]:
    """|τ| (T, 7) [Nm] of an exported Panda file by pinocchio's RNEA of the URDF, built here, and the
    URDF's effort limits (7,)."""
    urdf = example_robot_data_root() / "example-robot-data/robots/panda_description/urdf/panda.urdf"
    full = pin.buildModelFromUrdf(str(urdf))
    locked = [full.getJointId(name) for name in full.names[1:] if name not in PANDA_JOINTS]
    model = pin.buildReducedModel(full, locked, pin.neutral(full))
    data = model.createData()
    q, qd, qdd = exported_motion(csv, PANDA_JOINTS)
    tau = np.array([pin.rnea(model, data, *x) for x in zip(q, qd, qdd)])
    return np.abs(tau), model.effortLimit.copy()


def test_an_exported_motion_keeps_every_torque_within_its_limit(tmp_path):
    """The smoke problem with τ_max = 0.3 × the URDF's effort: every 1 kHz sample of the exported
    file (transitions included) within the limits by pinocchio's RNEA; without the limits the same
    problem's motion needs twice as much on joint 2, so the constraint is what keeps it."""
    uses = {}
    for name, torque in (("limited", 0.3), ("free", None)):
        config = yaml.safe_load((CONFIGS / "smoke.yaml").read_text())
        config["limits"]["torque"] = torque
        config["sequence"]["iterations"] = 1
        config["output"] = str(tmp_path / f"{name}.h5")
        (tmp_path / f"{name}.yaml").write_text(yaml.safe_dump(config))
        assert runner.invoke(app, ["optimize", str(tmp_path / f"{name}.yaml"), "--workers", "1"]).exit_code == 0
        played = tmp_path / f"{name}.csv"
        result = runner.invoke(app, ["export", str(tmp_path / f"{name}.h5"), "-o", str(played), "--rate", "1000"])
        assert result.exit_code == 0, result.output
        tau, effort = _panda_torques(played)
        uses[name] = (tau / (0.3 * effort)).max(axis=0)
    assert uses["limited"].max() <= 1.0
    assert uses["free"].max() > 1.5


def test_a_home_posture_beyond_the_torque_limits_stops_before_optimizing(tmp_path):
    config = yaml.safe_load((CONFIGS / "smoke.yaml").read_text())
    config["limits"]["torque"] = 0.01  # gravity alone needs more on the shoulder
    (tmp_path / "weak.yaml").write_text(yaml.safe_dump(config))
    assert_refused(tmp_path, ["optimize", str(tmp_path / "weak.yaml")], "limits.torque: violated before optimization")


@pytest.mark.parametrize(
    "torque, expected",
    [({"panda_joint9": 10.0}, "'panda_joint9' is not an active joint"), (-1.0, "limits.torque"), ("max", "torque")],
)
def test_a_torque_limit_that_cannot_be_is_refused(tmp_path, torque, expected):
    config = yaml.safe_load((CONFIGS / "smoke.yaml").read_text())
    config["limits"]["torque"] = torque
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(config))
    assert_refused(tmp_path, ["optimize", str(tmp_path / "bad.yaml")], expected)
