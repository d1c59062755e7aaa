"""Shared problem builders: the G1 arms, the Panda and a UR5, as validated Problems."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config import Problem, load_problem

CONFIGS = Path(__file__).resolve().parent.parent / "configs"

UR5 = {
    "robot": {
        "urdf": "ur_description/urdf/ur5_robot.urdf",
        "source": "example-robot-data",
        "active_joints": [
            "shoulder_pan_joint",
            "shoulder_lift_joint",
            "elbow_joint",
            "wrist_1_joint",
            "wrist_2_joint",
            "wrist_3_joint",
        ],
    },
    "trajectory": {
        "harmonics": 4,
        "base_frequency": 0.5,
        "cost_samples": 30,
        "cost_period": 0.3,
        "constraint_period": 0.05,
    },
    "limits": {"position_margin": 0.1, "acceleration": 4.0},
}


def small(problem: Problem, harmonics: int = 4, samples: int = 25) -> Problem:
    """The same robot with fewer harmonics and cost samples, so finite differences stay quick."""
    problem.trajectory.harmonics = harmonics
    problem.trajectory.cost_samples = samples
    problem.trajectory.cost_period = 8.0 / samples
    return problem


@pytest.fixture
def g1_problem() -> Problem:
    return load_problem(CONFIGS / "g1_arms.yaml")


@pytest.fixture
def panda_problem() -> Problem:
    return load_problem(CONFIGS / "panda.yaml")


@pytest.fixture
def ur5_problem(tmp_path: Path) -> Problem:
    path = tmp_path / "ur5.yaml"
    path.write_text(yaml.safe_dump(UR5))
    return load_problem(path)


def write_config(tmp_path: Path, data: dict, name: str = "problem.yaml") -> Path:
    """Write ``data`` as YAML in ``tmp_path`` and return the path."""
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def assert_refused(folder: Path, argv: list[str], expected: str) -> None:
    """``excite argv`` exits with status 2 and one line starting ``error:`` that contains
    ``expected``, prints no traceback, and writes or changes no file under ``folder``."""
    before = {p: p.stat().st_mtime_ns for p in folder.rglob("*")}
    result = CliRunner().invoke(app, argv, env={"COLUMNS": "400"})
    assert isinstance(result.exception, SystemExit), repr(result.exception)
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:"), result.output
    assert expected in lines[0], lines[0]
    assert "Traceback" not in result.output
    after = {p: p.stat().st_mtime_ns for p in folder.rglob("*")}
    assert after == before, f"files written or changed: {sorted(set(after) ^ set(before))}"
