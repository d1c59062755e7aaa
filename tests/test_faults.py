"""Faults beyond bad config values (issue 20): SIGTERM during a parallel run, robots that cannot be,
robots with one active joint. Each bad case must exit with status 2 and one line naming the field,
print no traceback and leave no file behind; the good ones must work."""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml
from conftest import assert_refused, pendulum_config
from typer.testing import CliRunner

from excite_cli.cli import app

runner = CliRunner()
EXCITE = Path(sys.executable).with_name("excite")
CONFIGS = Path(__file__).resolve().parent.parent / "configs"

URDF_CASES = [
    ("negative-mass", {"mass": "-1.5"}, "link 'arm' has a negative mass"),
    ("nan-mass", {"mass": "nan"}, "link 'arm': mass value is 'nan'"),
    ("text-mass", {"mass": "heavy"}, "link 'arm': mass value is 'heavy'"),
    ("inf-inertia", {"izz": "inf"}, "link 'arm': inertia izz is 'inf'"),
    ("negative-moment", {"izz": "-0.01"}, "link 'arm' has an inertia no body can have"),
    ("triangle", {"izz": "0.2"}, "link 'arm' has an inertia no body can have"),
    ("held-link-negative-mass", {"tip_mass": "-0.2"}, "link 'tip' has a negative mass"),
    ("moved-held-link-triangle", {"tip_ixx": "1e-2"}, "link 'tip' has an inertia no body can have"),
    ("limits-crossed", {"lower": "3.0"}, "joint 'hinge' has lower limit 3 above upper 2"),
    ("nan-velocity-limit", {"velocity": "nan"}, "joint 'hinge': limit velocity is 'nan'"),
    # a link with two parent joints (pinocchio said "'j1' is not a joint of the robot" or "no body named tip")
    (
        "kinematic-loop",
        {"mimic": '</joint><joint name="loop" type="revolute"><parent link="tip"/><child link="arm"/>'},
        "robot.urdf: link 'arm' is the child of 2 joints ('hinge', 'loop'): a closed kinematic chain",
    ),
    # the follower of an active joint, held still while its leader moves (it was, silently)
    (
        "mimic-follower-held",
        {"mimic": '<mimic joint="hinge" multiplier="2"/>'},
        "robot.locked_joints: joint 'tip_joint' mimics active joint 'hinge' (multiplier 2, offset 0)",
    ),
]


@pytest.mark.parametrize("urdf", [c[1] for c in URDF_CASES], ids=[c[0] for c in URDF_CASES])
@pytest.mark.parametrize("command", ["optimize", "verify-gradient"])
def test_a_robot_that_cannot_be_is_refused_by_name(tmp_path, command, urdf):
    expected = dict((tuple(c[1].items()), c[2]) for c in URDF_CASES)[tuple(urdf.items())]
    config = pendulum_config(tmp_path, **urdf)
    assert_refused(tmp_path, [command, str(config)], expected)


def test_a_link_no_active_joint_moves_may_break_the_triangle_inequality(tmp_path):
    """Real URDFs do (the PR2's sensor mounts, Romeo's torso): only the moved links are held to it."""
    config = pendulum_config(tmp_path, active=("tip_joint",), izz="0.2")  # the arm, held, breaks it
    result = runner.invoke(app, ["optimize", str(config)])
    assert result.exit_code == 0, result.output


def test_a_one_joint_pendulum_optimizes_simulates_and_identifies(tmp_path):
    """The one-joint regressor comes back from pinocchio flat: any number of active joints ≥ 1 works.
    Simulated Coulomb 0.3 Nm and viscous 0.2 Nm·s/rad are found within 5 %."""
    config = pendulum_config(tmp_path, iterations=2)
    assert runner.invoke(app, ["optimize", str(config)]).exit_code == 0
    with h5py.File(tmp_path / "out.h5") as f:
        assert f["iterations/2/regressor"].shape[1] == 3  # m z, m x, I_yy of the arm (its tip held)
    effects = tmp_path / "effects.yaml"
    effects.write_text(
        yaml.safe_dump(
            {
                "sample_rate": 200.0,
                "periods": 3,
                "torque_noise": 0.02,
                "seed": 3,
                "effects": {"coulomb": {"*": 0.3}, "viscous": {"*": 0.2}},
            }
        )
    )
    sim = runner.invoke(app, ["simulate", str(tmp_path / "out.h5"), str(effects), "-o", str(tmp_path / "sim")])
    assert sim.exit_code == 0, sim.output
    identify = {
        "robot": {"urdf": "pendulum.urdf", "active_joints": ["hinge"]},
        "data": {
            "runs": [{"file": "sim/run_1.csv", "role": "fit"}, {"file": "sim/run_2.csv", "role": "validation"}],
            "columns": {"q": ["q_hinge"], "tau": ["tau_hinge"]},
        },
        "output": str(tmp_path / "id.h5"),
    }
    (tmp_path / "id.yaml").write_text(yaml.safe_dump(identify))
    result = runner.invoke(app, ["identify", str(tmp_path / "id.yaml")])
    assert result.exit_code == 0, result.output
    with h5py.File(tmp_path / "id.h5") as f:
        effects_found = {row["coefficient"].decode(): row["value"] for row in f["identification/effects"][()]}
        relative_after = f["identification/relative_after"][()]
    assert effects_found["Fc"] == pytest.approx(0.3, rel=0.05) and effects_found["Fv"] == pytest.approx(0.2, rel=0.05)
    assert relative_after[0] < 2.0


def test_one_joint_of_a_real_arm_optimizes(tmp_path):
    """A single active joint of the Panda, the others held at their reference."""
    config = yaml.safe_load((CONFIGS / "smoke.yaml").read_text())
    config["robot"]["active_joints"] = ["panda_joint4"]
    config["sequence"]["iterations"] = 1
    config["output"] = str(tmp_path / "one.h5")
    (tmp_path / "one.yaml").write_text(yaml.safe_dump(config))
    result = runner.invoke(app, ["optimize", str(tmp_path / "one.yaml")])
    assert result.exit_code == 0, result.output
    with h5py.File(tmp_path / "one.h5") as f:
        assert np.isfinite(f["iterations/1"].attrs["cond_stacked"])


def _children(pid: int) -> list[int]:
    """Processes whose parent is ``pid`` (Linux /proc)."""
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                out.append(int(entry.name))
    return out


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc to find the worker processes")
@pytest.mark.end_to_end
def test_sigterm_during_a_two_worker_optimize_stops_everything_and_keeps_finished_iterations(tmp_path):
    config = yaml.safe_load((CONFIGS / "smoke.yaml").read_text())
    config["trajectory"]["harmonics"] = 5
    config["optimizer"].update(max_iterations=300, restarts=2)
    config["sequence"]["iterations"] = 6
    config["output"] = str(tmp_path / "run.h5")
    (tmp_path / "run.yaml").write_text(yaml.safe_dump(config))
    process = subprocess.Popen(
        [str(EXCITE), "optimize", str(tmp_path / "run.yaml"), "--workers", "2"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 240
    while not (tmp_path / "run.h5").exists() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.2)
    workers = _children(process.pid)
    assert process.poll() is None and len(workers) >= 2, "the run ended before the first iteration was written"
    time.sleep(0.5)
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 143, stderr
    kept = int(re.search(r"terminated: kept (\d+) finished iteration", stderr).group(1))
    time.sleep(5)
    assert [pid for pid in workers if Path(f"/proc/{pid}").exists() and _alive(pid)] == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.h5", "run.yaml"]  # no .partial, no plots
    with h5py.File(tmp_path / "run.h5") as f:
        assert len(f["iterations"]) == kept >= 1
    assert "Traceback" not in stderr


def _alive(pid: int) -> bool:
    """A process that has not ended (a zombie has: it only waits to be reaped)."""
    try:
        return (Path(f"/proc/{pid}") / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_sigterm_is_restored_after_a_command():
    before = signal.getsignal(signal.SIGTERM)
    runner.invoke(app, ["verify-gradient", "--help"])
    assert signal.getsignal(signal.SIGTERM) == before


def _identify_config(folder: Path) -> Path:
    pendulum_config(folder)
    config = {
        "robot": {"urdf": "pendulum.urdf", "active_joints": ["hinge"]},
        "data": {"runs": [{"file": "run.csv"}], "columns": {"q": ["q_hinge"], "tau": ["tau_hinge"]}},
    }
    (folder / "id.yaml").write_text(yaml.safe_dump(config))
    return folder / "id.yaml"


@pytest.mark.parametrize("option", ["--urdf-out", "--mjcf-out"])
@pytest.mark.parametrize("model", ["report.h5", "report_residuals.png", "report_ladder.png"])
def test_the_identified_model_may_not_overwrite_the_report_or_its_plots(tmp_path, option, model):
    config = _identify_config(tmp_path)
    argv = ["identify", str(config), "-o", str(tmp_path / "report.h5"), option, str(tmp_path / model)]
    line = assert_refused(tmp_path, argv, "is also the report or one of its plots")
    assert line.startswith(f"error: {option}: ")


@pytest.mark.parametrize("case", ["same", "folder", "unwritable", "fifo", "proc"])
def test_a_bad_mjcf_path_is_one_line_before_anything_runs(tmp_path, case):
    """ "proc": a folder that access() calls writable for root, where no file can be created."""
    if case == "proc" and not Path("/proc/self").is_dir():
        pytest.skip("needs /proc")
    config = _identify_config(tmp_path)
    target = {"same": tmp_path / "m.xml", "folder": tmp_path, "unwritable": config / "m.xml"}.get(case)
    target = Path("/proc/m.xml") if case == "proc" else target
    if case == "fifo":
        target = tmp_path / "m.xml"
        os.mkfifo(target)
    argv = ["identify", str(config), "-o", str(tmp_path / "r.h5"), "--mjcf-out", str(target), "--force"]
    if case == "same":
        argv += ["--urdf-out", str(target)]
    expected = {
        "same": "is also the other model file",
        "folder": "folder",
        "unwritable": "is a file",
        "proc": "cannot create a file in /proc",
    }
    assert_refused(tmp_path, argv, expected.get(case, "is not a regular file"))


@pytest.mark.parametrize("command", ["optimize", "identify"])
def test_an_output_that_is_not_a_regular_file_is_never_replaced(tmp_path, command):
    fifo = tmp_path / "fifo.h5"
    os.mkfifo(fifo)
    config = pendulum_config(tmp_path) if command == "optimize" else _identify_config(tmp_path)
    assert_refused(tmp_path, [command, str(config), "-o", str(fifo), "--force"], "is not a regular file")
    assert fifo.is_fifo()


@pytest.mark.parametrize("tolerance", ["nan", "inf", "-1e-6", "0"])
def test_verify_gradient_needs_a_pass_mark_that_can_fail(tmp_path, tolerance):
    assert_refused(tmp_path, ["verify-gradient", str(pendulum_config(tmp_path)), "--tolerance", tolerance], "tolerance")


@pytest.mark.parametrize("command", ["optimize", "verify-gradient"])
def test_an_active_mimic_joint_is_refused_by_name(tmp_path, command):
    config = pendulum_config(tmp_path, active=("tip_joint",), mimic='<mimic joint="hinge"/>')
    assert_refused(tmp_path, [command, str(config)], "joint 'tip_joint' mimics 'hinge'")


# --- URDFs init cannot use: one line, in a bounded time, whatever pinocchio or assimp would do ------


def _hostile_urdf(folder: Path, case: str) -> Path:
    """A URDF of ``case``: no joint, only fixed joints, a joint type urdfdom does
    not know, a collision mesh that is not a mesh, a FIFO, or too large (sparse), a chain longer than
    pinocchio's parser holds."""
    inertia = '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>'
    link = '<link name="{}"><inertial><mass value="1"/>' + inertia + "</inertial>{}</link>"
    joint = (
        '<joint name="{}" type="{}"><parent link="{}"/><child link="{}"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="10" velocity="2"/></joint>'
    )

    def two_links(kind: str, mesh: str = "") -> str:
        collision = f'<collision><geometry><mesh filename="{mesh}"/></geometry></collision>' if mesh else ""
        return link.format("base", "") + link.format("arm", collision) + joint.format("j1", kind, "base", "arm")

    if case == "fifo":
        os.mkfifo(folder / "fifo.stl")
    if case == "huge-mesh":
        with open(folder / "huge.stl", "wb") as f:
            f.truncate(2 * 1024**3)  # sparse: no disk used
    body = {
        "no-joint": link.format("base", ""),
        "fixed-only": two_links("fixed"),
        "not-a-mesh": two_links("revolute", "file:///etc/passwd"),
        "fifo": two_links("revolute", "fifo.stl"),
        "huge-mesh": two_links("revolute", "huge.stl"),
        "unknown-joint-type": two_links("bogus"),
        "long-chain": link.format("l0", "")
        + "".join(
            link.format(f"l{k}", "") + joint.format(f"j{k}", "revolute", f"l{k - 1}", f"l{k}") for k in range(1, 4001)
        ),
    }[case]
    path = folder / f"{case}.urdf"
    path.write_text(f'<robot name="hostile">{body}</robot>')
    return path


HOSTILE = [
    ("no-joint", "no-joint.urdf has no revolute joint for excite to move (its joints are all fixed)"),
    ("fixed-only", "fixed-only.urdf has no revolute joint for excite to move (its joints are all fixed)"),
    ("long-chain", "the URDF has 4001 links; expected at most 1000"),
    ("unknown-joint-type", "does not contain a valid URDF model"),  # pinocchio's ValueError was a traceback
]
#: Meshes matter to an optimize config only (an identify config loads none).
HOSTILE_MESHES = [
    ("not-a-mesh", "cannot load the collision meshes of not-a-mesh.urdf"),
    ("fifo", "link 'arm': collision mesh fifo.stl"),
    ("huge-mesh", "link 'arm': collision mesh huge.stl is 2147 MB"),
]
HOSTILE_RUNS = [(*c, k) for c in HOSTILE for k in ("optimize", "identify")] + [(*c, "optimize") for c in HOSTILE_MESHES]


@pytest.mark.parametrize("case, expected, kind", HOSTILE_RUNS, ids=[f"{c[0]}-{c[2]}" for c in HOSTILE_RUNS])
def test_init_on_a_urdf_it_cannot_use_is_one_line(tmp_path, case, expected, kind):
    """Each was a traceback (min() of an empty sequence, pydantic, coal, assimp), a hang on the FIFO,
    7.4 GB of memory on the 2 GB mesh, or a segmentation fault (a chain of 4 000 links)."""
    urdf = _hostile_urdf(tmp_path, case)
    process = subprocess.run(
        [str(EXCITE), "init", str(urdf), "--kind", kind, "-o", str(tmp_path / "out.yaml")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert process.returncode == 2, process.stderr
    assert "Traceback" not in process.stderr + process.stdout
    errors = [line for line in process.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and expected in errors[0], process.stderr
    assert not (tmp_path / "out.yaml").exists()


def test_a_ring_of_joints_beside_the_tree_is_named(tmp_path):
    """Two links joined both ways apart from the pendulum: pinocchio leaves them out, and the ring's
    joint was reported as "'ab' is not a joint of the robot"."""
    ring = (
        '</joint><link name="a"/><link name="b"/>'
        '<joint name="ab" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>'
        '<joint name="ba" type="revolute"><parent link="b"/><child link="a"/><axis xyz="0 0 1"/>'
    )
    config = pendulum_config(tmp_path, active=("hinge", "ab"), mimic=ring)
    assert_refused(tmp_path, ["optimize", str(config)], "joints 'ba', 'ab' form a closed kinematic chain")
