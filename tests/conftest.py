"""Shared problem builders: the G1 arms, the Panda and a UR5, as validated Problems."""

from __future__ import annotations

import functools
import socket
import threading
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import Iterator

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config import Problem
from excite_cli.config_file import load_problem
from excite_cli.dynamics.robot import load_robot

TESTS = Path(__file__).resolve().parent
CONFIGS = TESTS.parent / "configs"
#: The real Panda run of ../shared (not in the repository).
SHARED = TESTS.parent.parent / "shared" / "data" / "panda-gaz2019"
JOINTS = [f"panda_joint{k}" for k in range(1, 8)]
#: Torque noise of the simulated identification runs [Nm].
NOISE = 0.05

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


def robot_of(problem, collision: bool = False):
    """The Robot of a validated problem (optimize or identify config)."""
    return load_robot(problem.robot, problem.folder, collision)


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
    return load_problem(CONFIGS / "panda_joint_limits.yaml")


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


def smoke_config(folder: Path) -> dict:
    """The smoke problem (configs/smoke.yaml) with its output in ``folder``: a run or a refusal never
    meets the checkout's own results/smoke.h5 (which the smoke run of .ci/run writes, so that an
    "output exists" refusal came first in a checkout that had run it)."""
    data = yaml.safe_load((CONFIGS / "smoke.yaml").read_text())
    data["output"] = str(folder / "out.h5")
    return data


def panda_runs_config(runs: list[str], **identification) -> dict:
    """An identify config of the Panda's simulated runs ``runs`` (CSV files of ``excite simulate``), each
    fitted and validated on alternate time blocks, with ``identification`` settings."""
    return {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {
            "runs": [{"file": f, "role": "blocks"} for f in runs],
            "columns": {"q": [f"q_{j}" for j in JOINTS], "tau": [f"tau_{j}" for j in JOINTS]},
        },
        "identification": identification,
    }


def assert_refused(folder: Path, argv: list[str], expected: str) -> str:
    """``excite argv`` exits with status 2 and one line starting ``error:`` that contains
    ``expected``, prints no traceback, and writes or changes no file under ``folder``; that line."""
    before = {p: p.lstat().st_mtime_ns for p in folder.rglob("*")}  # a link itself, not what it points to
    result = CliRunner().invoke(app, argv, env={"COLUMNS": "400"})
    assert isinstance(result.exception, SystemExit), repr(result.exception)
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:"), result.output
    assert expected in lines[0], lines[0]
    assert "Traceback" not in result.output
    after = {p: p.lstat().st_mtime_ns for p in folder.rglob("*")}
    assert after == before, f"files written or changed: {sorted(set(after) ^ set(before))}"
    return lines[0]


PENDULUM = """<?xml version="1.0"?>
<robot name="pendulum">
  <link name="base"/>
  <link name="arm">
    <inertial><origin xyz="0 0 -0.25"/><mass value="{mass}"/>
      <inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="{izz}"/></inertial>
  </link>
  <link name="tip">
    <inertial><mass value="{tip_mass}"/><inertia ixx="{tip_ixx}" iyy="1e-4" izz="1e-4"/></inertial>
  </link>
  <joint name="hinge" type="revolute">
    <parent link="base"/><child link="arm"/><axis xyz="0 1 0"/>
    <limit lower="{lower}" upper="2.0" effort="20" velocity="{velocity}"/>
  </joint>
  <joint name="tip_joint" type="revolute">
    <parent link="arm"/><child link="tip"/><origin xyz="0 0 -0.5"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="5" velocity="3"/>{mimic}
  </joint>
</robot>
"""
GOOD = {"mass": "1.5", "izz": "0.002", "tip_mass": "0.2", "tip_ixx": "1e-4", "lower": "-2.0", "velocity": "3"}


def pendulum_config(folder: Path, active=("hinge",), iterations=1, changes: dict | None = None, **urdf) -> Path:
    """A config of the pendulum URDF (its tip held unless active), written beside it, with dotted
    ``changes`` (``{"trajectory.base_frequency": 1e-9}``) and URDF fields ``urdf`` (see ``GOOD``)."""
    (folder / "pendulum.urdf").write_text(PENDULUM.format(**{**GOOD, "mimic": "", **urdf}))
    config = {
        "robot": {"urdf": "pendulum.urdf", "active_joints": list(active)},
        "trajectory": {"harmonics": 3, "base_frequency": 0.6283185307179586},
        "limits": {"velocity": 1.5, "acceleration": 5.0},
        "optimizer": {"max_iterations": 40, "restarts": 1, "workers": 1},
        "sequence": {"iterations": iterations},
        "output": str(folder / "out.h5"),
    }
    for dotted, value in (changes or {}).items():
        *sections, name = dotted.split(".")
        functools.reduce(lambda d, k: d.setdefault(k, {}), sections, config)[name] = value
    path = folder / "pendulum.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


def exported_motion(path: Path, joints: list[str]) -> tuple:
    """q, q̇, q̈ (T, n) [rad, rad/s, rad/s²] of the joints of an ``excite export`` CSV, read here."""
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    header, table = lines[0].split(","), np.loadtxt(lines[1:], delimiter=",")
    units = {"q": "rad", "qd": "rad_s", "qdd": "rad_s2"}
    return tuple(table[:, [header.index(f"{x}_{j}_{u}") for j in joints]] for x, u in units.items())


def constraint_jacobian_error(constraint, alpha: np.ndarray, step: float = 1e-6) -> float:
    """Largest difference between ``constraint``'s Jacobian at α and central differences of its
    values, relative to the largest difference."""
    jacobian = constraint.evaluate(alpha)[1]
    flat, differences = alpha.ravel(), np.empty_like(jacobian)
    for k in range(flat.size):
        e = np.zeros_like(flat)
        e[k] = step
        plus, minus = (constraint.evaluate((flat + s * e).reshape(alpha.shape))[0] for s in (1, -1))
        differences[:, k] = (plus - minus) / (2 * step)
    return float(np.abs(jacobian - differences).max() / np.abs(differences).max())


@pytest.fixture(scope="module")
def optimized(tmp_path_factory):
    """A small optimized Panda result with 3 trajectories."""
    tmp = tmp_path_factory.mktemp("opt")
    data = yaml.safe_load((CONFIGS / "smoke.yaml").read_text())
    data.update(sequence={"iterations": 3}, output=str(tmp / "panda.h5"))
    data["optimizer"]["objective"] = "log_det"  # the motions the identification tests' margins were set on
    result = CliRunner().invoke(app, ["optimize", str(write_config(tmp, data))])
    assert result.exit_code == 0, result.output
    return tmp / "panda.h5"


@pytest.fixture(scope="session")
def simulated_identification():
    """``identify`` of the shipped simulated Panda runs (Coulomb and viscous friction undeclared):
    (problem, report, robot, base, prior rows), as the pipeline returns them (the report file empties
    the rows' parts it writes: give it :func:`rows_copy`)."""
    from excite_cli.identification.config import IdentifyProblem
    from excite_cli.identification.pipeline import run_identification

    problem = load_problem(CONFIGS / "panda_identify_simulated.yaml", IdentifyProblem)
    return (problem, *run_identification(problem))


@pytest.fixture(scope="module")
def report_file(simulated_identification, tmp_path_factory):
    """The report file of :func:`simulated_identification` (friction found on every joint)."""
    from excite_cli.identification.reporting.report_file import write_identification

    problem, report, robot, base, rows = simulated_identification
    path = tmp_path_factory.mktemp("report") / "report.h5"
    write_identification(path, report, robot, base, problem, rows_copy(rows))
    return path


@contextmanager
def tcp_server(first_bytes: bytes) -> Iterator[str]:
    """A TCP server on a free local port that sends ``first_bytes`` to whoever connects, then stays
    silent: its address."""
    listener = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve() -> None:
        connection, _ = listener.accept()
        with connection:
            connection.sendall(first_bytes)
            stop.wait(10)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{listener.getsockname()[1]}"
    finally:
        stop.set()
        listener.close()


def rows_copy(rows):
    """A copy of an identification's prior rows (``PriorRows``) whose parts the report file may empty."""
    return replace(rows, regressor=[part.copy() for part in rows.regressor], effects=[p.copy() for p in rows.effects])


def panda_mjcf(folder: Path, frames: bool = False) -> Path:
    """example-robot-data's Panda as MJCF, written by MuJoCo from the URDF (its inertias, its collision
    meshes by absolute path, the fingers' mimic as a joint equality), as ``folder/panda.xml``; with
    ``frames``, MuJoCo's fixed links as ``<frame>`` elements (what ``MjSpec.to_xml`` writes by default)."""
    import mujoco

    from excite_cli.dynamics.robot_files import example_robot_data_root

    share = example_robot_data_root()
    text = (share / "example-robot-data/robots/panda_description/urdf/panda.urdf").read_text()
    compiler = '<mujoco><compiler fusestatic="false" discardvisual="true"/></mujoco>' if not frames else ""
    urdf = folder / "panda_for_mujoco.urdf"
    urdf.write_text(text.replace("package://", f"{share}/").replace("</robot>", f"{compiler}</robot>"))
    spec = mujoco.MjSpec.from_file(str(urdf))
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    spec.compile()
    (folder / "panda.xml").write_text(spec.to_xml())
    urdf.unlink()
    return folder / "panda.xml"


CHAIN_INERTIAL = (
    '<inertial><mass value="0.5"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial>'
)


def chain_urdf(arm: list[str], gripper: bool = True) -> str:
    """An arm of revolute (or continuous) joints ``arm`` (joint types) on a base, and a gripper as Kinova's
    Gen3 lite has one: a fixed gripper base, a right finger on a revolute joint, a left finger whose joint
    mimics it, each with a tip joint that mimics it too."""
    links, joints = ['<link name="base_link"/>'], []

    def joint(name: str, kind: str, parent: str, child: str, mimic: str = "") -> None:
        links.append(f'<link name="{child}">{CHAIN_INERTIAL}</link>')
        limit = '<limit lower="-2" upper="2" effort="10" velocity="1"/>' if kind != "fixed" else ""
        follows = f'<mimic joint="{mimic}"/>' if mimic else ""
        joints.append(
            f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="0 0 0.1"/><axis xyz="0 {k % 2} {1 - k % 2}"/>{limit}{follows}</joint>'
        )

    for k, kind in enumerate(arm, start=1):
        joint(f"joint_{k}", kind, "base_link" if k == 1 else f"link_{k - 1}", f"link_{k}")
    if gripper:
        k = len(arm) + 1
        joint("gripper_base_joint", "fixed", f"link_{len(arm)}", "gripper_base_link")
        joint("right_finger_bottom_joint", "revolute", "gripper_base_link", "right_prox_link")
        joint("right_finger_tip_joint", "revolute", "right_prox_link", "right_dist_link", "right_finger_bottom_joint")
        joint(
            "left_finger_bottom_joint", "revolute", "gripper_base_link", "left_prox_link", "right_finger_bottom_joint"
        )
        joint("left_finger_tip_joint", "revolute", "left_prox_link", "left_dist_link", "right_finger_bottom_joint")
    return f'<robot name="arm">{"".join(links)}{"".join(joints)}</robot>'


ARM_WITH_PARTS = """<mujoco model="arm"><compiler angle="degree"/><default><joint damping="0.1"/></default>
  <worldbody><geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="link1" pos="0 0 0.1"><joint name="joint1" axis="0 0 1" range="-170 170"/>
      <geom type="cylinder" size="0.05 0.1" mass="2"/><include file="{include}"/></body>
  </worldbody>
  <actuator><motor joint="joint1" gear="50" ctrlrange="-1 1" ctrllimited="true"/>
    <motor joint="joint2" forcerange="-40 40" forcelimited="true"/>
    <general joint="joint3" gear="10" ctrlrange="-2 2"/>
    <position joint="joint3" kp="100" ctrlrange="-1 1"/></actuator>
</mujoco>"""
PARTS = """<mujoco><body name="link2" pos="0 0 0.3">
    <joint name="joint2" axis="0 1 0" range="-90 90" damping="0.5" frictionloss="0.2" armature="0.01"/>
    <geom type="capsule" fromto="0 0 0 0.05 0 0.3" size="0.04" mass="1.5"/>
    <frame pos="0 0.02 0.3" euler="0 0 90"><body name="link3"><joint name="joint3" axis="0 1 0" pos="0 0 0.02"
      range="-90 90"/><geom type="box" size="0.03 0.02 0.1" pos="0.01 0 0.1" mass="0.8"/></body></frame>
</body></mujoco>"""


def included_arm_mjcf(folder: Path, include: str = "parts.xml", name: str = "arm.xml") -> Path:
    """A 3-joint MJCF arm as a lab writes one: joints 2 and 3 in an included file, joint 3's body in a
    <frame>, a floor in <worldbody>, a default class, damping and frictionloss, and actuators of
    three kinds (a motor with gear 50 and ctrlrange 1: 50 N·m; forcerange 40 N·m; a general actuator
    with gear 10 and ctrlrange 2: 20 N·m; a position servo, whose range is a position), as
    ``folder/name`` including ``folder/include`` (written only when it is ``parts.xml``)."""
    if include == "parts.xml":
        (folder / include).write_text(PARTS)
    (folder / name).write_text(ARM_WITH_PARTS.format(include=include))
    return folder / name


def made_rehearsal(standing: bool = True, fell: bool = False, tau_peak: float = 1.0):
    """A :class:`~excite_cli.rehearsal.report.Rehearsal` of one iteration made by hand: two joints (limit
    2 N·m, ``tau_peak`` reached on the second), 1 s at 100 Hz; standing, a centre of pressure circling 3 cm
    inside a 10 cm square, beside PD alone circling 6 cm, the base dropping 6 cm where it ``fell``."""
    from excite_cli.config.rehearsal import RehearsalConfig
    from excite_cli.constraints.support import SupportPolygon
    from excite_cli.rehearsal.playing import Played
    from excite_cli.rehearsal.report import IterationRehearsal, Rehearsal
    from excite_cli.storage.export import Export

    time = np.arange(100) / 100.0
    q = np.column_stack([np.sin(time), np.cos(time)])
    tau = np.column_stack([0.5 * np.sin(time), tau_peak * np.cos(time)])
    export = Export(["a", "b"], time, q, q, q, tau, 100.0, 1, 1, [("trajectory", 0.0, 1.0)], -1.0, "")
    none = np.zeros((100, 0))
    circle = np.column_stack([np.cos(2 * np.pi * time), np.sin(2 * np.pi * time)])
    fields = {}
    if standing:
        square = SupportPolygon.from_points(np.array([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]), 0.0)
        drop = time * (0.06 if fell else 0.0)
        fields = dict(com=0 * circle, polygon=square, sole_tilt=0 * time, root_tilt=0 * time, drop=drop)
    played = Played(time, q + 1e-3, q, tau, none, {}, (), cop=0.07 * circle if standing else None, **fields)
    alone = Played(time, q, q, tau, none, {}, (), cop=0.04 * circle, **fields) if standing else None
    predicted = 0.07 * circle if standing else None
    it = IterationRehearsal(1, export, played, alone, np.array([2.0, 2.0]), np.zeros(0), predicted)
    return Rehearsal(Path("r.h5"), RehearsalConfig(), [it], Path("robot.urdf"), plot=Path("r_rehearsal.png"))
