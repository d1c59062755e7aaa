"""`excite check` and `optimize --dry-run`: the problem optimize would run, counted against independent
truth (the regressor's numerical rank, the Fourier coefficients, the capsule pairs), nothing written,
and what optimize would refuse refused the same way."""

import numpy as np
import yaml
from conftest import CONFIGS, assert_refused
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.workflows.check import plan_optimize

runner = CliRunner()


def test_the_plan_counts_what_optimize_would_build(tmp_path):
    """The Panda as shipped, plus a ceiling 3 m up that no link of an arm about 1.2 m long can come near:
    named as adding no rows (the table does)."""
    config = yaml.safe_load((CONFIGS / "panda.yaml").read_text())
    ceiling = {"name": "ceiling", "type": "half_space", "point": [0, 0, 3], "normal": [0, 0, -1], "margin": 0.02}
    config["constraints"]["environment"]["shapes"].append(ceiling)
    (tmp_path / "panda.yaml").write_text(yaml.safe_dump(config))
    problem = load_problem(tmp_path / "panda.yaml")
    plan = plan_optimize(problem)
    assert plan.unreached == ["ceiling"]
    robot = plan.excitation.robot
    Y = np.vstack([robot.regressor(*x) for x in zip(*robot.random_states(30, np.random.default_rng(0)))])
    assert plan.excitation.base.count == np.linalg.matrix_rank(Y) == 43  # the Panda's base parameters
    assert plan.variables == 7 * (2 * problem.trajectory.harmonics + 1)
    sizes = {c.name: c.rows for c in plan.constraints}
    assert sizes["joint_limits"] == 6 * 7 and sizes["torque_limits"] > 0
    capsules = plan.excitation.constraints[2].capsules
    links = {frozenset((capsules[i].link, capsules[j].link)) for i, j in plan.excitation.constraints[2].pairs}
    assert sizes["self_collision"] == len(plan.excitation.constraints[2].pairs) and links
    assert not links & {frozenset(p) for p in problem.constraints.self_collision.exclude_pairs}
    assert plan.excluded_pairs == [tuple(p) for p in problem.constraints.self_collision.exclude_pairs]
    assert plan.iterations == problem.optimizer.planned_iterations and plan.estimate > 0


def test_check_and_dry_run_print_the_plan_and_write_nothing(tmp_path):
    config = tmp_path / "panda.yaml"
    config.write_text((CONFIGS / "panda_joint_limits.yaml").read_text())
    for argv in (["check", str(config)], ["optimize", str(config), "--dry-run", "-o", str(tmp_path / "r.h5")]):
        result = runner.invoke(app, argv, env={"COLUMNS": "200"})
        assert result.exit_code == 0, result.output
        assert "43 base parameters of 70 standard ones" in result.output and "estimated time: about" in result.output
        assert "joint_limits │   42" in result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["panda.yaml"]


def test_what_optimize_would_refuse_is_refused_by_the_check(tmp_path):
    data = yaml.safe_load((CONFIGS / "panda.yaml").read_text())
    data["constraints"]["environment"]["shapes"][0]["point"] = [0, 0, 0.5]  # a table through the arm
    (tmp_path / "raised.yaml").write_text(yaml.safe_dump(data))
    for argv in (["check"], ["optimize", "--dry-run"]):
        line = assert_refused(tmp_path, [*argv, str(tmp_path / "raised.yaml")], "violated before optimization")
        assert "constraints.environment" in line
