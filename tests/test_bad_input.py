"""Bad input over every command, as a new user would give it: each case must exit with status 2 and
one line naming the field or option, print no traceback, leave no file behind, and leave an existing
output untouched."""

import copy

import h5py
import numpy as np
import pytest
import yaml
from conftest import UR5, assert_refused, robot_of
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem

runner = CliRunner()
JOINTS = UR5["robot"]["active_joints"]


def _small(**edits):
    data = copy.deepcopy(UR5)
    data["trajectory"].update(harmonics=3, cost_samples=20, cost_period=0.4, constraint_period=0.05)
    data["optimizer"] = {"max_iterations": 15, "restarts": 1, "workers": 1}
    data["sequence"] = {"iterations": 1}
    for dotted, value in edits.items():
        *parents, last = dotted.split(".")
        node = data
        for part in parents:
            node = node.setdefault(part, {})
        node[last] = value
    return data


def _csv(path, rows=3000, rate=500.0, still=False, nan_at=None):
    """A run of the UR5 with RNEA torques, columns time, q_<joint>, tau_<joint>."""
    robot = robot_of(load_problem(_yaml(path.parent / "robot.yaml", _small())))
    t = np.arange(rows) / rate
    q = 0.0 * np.outer(t, np.ones(6)) if still else 0.5 * np.sin(np.outer(t, np.arange(1, 7)))
    qd, qdd = np.gradient(q, t, axis=0), np.gradient(np.gradient(q, t, axis=0), t, axis=0)
    tau = np.array([robot.torques(*x) for x in zip(q, qd, qdd)])
    table = np.column_stack([t, q, tau])
    if nan_at is not None:
        table[nan_at, 2] = np.nan
    header = ",".join(["time"] + [f"q_{j}" for j in JOINTS] + [f"tau_{j}" for j in JOINTS])
    np.savetxt(path, table, delimiter=",", header=header, comments="", fmt="%.10g")
    return path


def _identify_config(tmp, run="run.csv", **edits):
    data = {
        "robot": {k: UR5["robot"][k] for k in ("urdf", "source", "active_joints")},
        "data": {
            "runs": [{"file": run, "role": "fit"}, {"file": run, "role": "validation"}],
            "columns": {"q": [f"q_{j}" for j in JOINTS], "tau": [f"tau_{j}" for j in JOINTS]},
        },
        "output": str(tmp / "report.h5"),
    }
    for dotted, value in edits.items():
        section, name = dotted.split(".")
        data.setdefault(section, {})[name] = value
    return _yaml(tmp / "identify.yaml", data)


def _yaml(path, data):
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.fixture(scope="module")
def shared(tmp_path_factory):
    """A result of the small UR5 problem and one of another robot (the Panda)."""
    tmp = tmp_path_factory.mktemp("shared")
    result = tmp / "ur5.h5"
    assert runner.invoke(app, ["optimize", str(_yaml(tmp / "ur5.yaml", _small())), "-o", str(result)]).exit_code == 0
    panda = _small(
        **{
            "robot.urdf": "panda_description/urdf/panda.urdf",
            "robot.active_joints": [f"panda_joint{k}" for k in range(1, 8)],
        }
    )
    other = tmp / "panda.h5"
    assert runner.invoke(app, ["optimize", str(_yaml(tmp / "panda.yaml", panda)), "-o", str(other)]).exit_code == 0
    garbage = tmp / "garbage.h5"
    garbage.write_bytes(b"\x89HDF\x00 not really" * 10)
    notresult = tmp / "plain.h5"
    with h5py.File(notresult, "w") as f:
        f["x"] = np.zeros(3)
    return {"result": result, "other": other, "garbage": garbage, "plain": notresult}


def _optimize_config(tmp, **edits):
    return ["optimize", str(_yaml(tmp / "bad.yaml", _small(**edits))), "-o", str(tmp / "out.h5")]


def _raw(tmp, text, name="bad.yaml"):
    path = tmp / name
    path.write_bytes(text) if isinstance(text, bytes) else path.write_text(text)
    return ["optimize", str(path), "-o", str(tmp / "out.h5")]


# (case id, builder(tmp, shared) -> argv, expected fragment of the one-line message)
CASES = [
    ("yaml-malformed", lambda t, s: _raw(t, "robot: [unclosed\n"), "line"),
    ("yaml-empty", lambda t, s: _raw(t, ""), "empty file; expected a mapping"),
    ("yaml-list", lambda t, s: _raw(t, "- a\n- b\n"), "mapping"),
    ("yaml-binary", lambda t, s: _raw(t, b"\xff\xfe\x00\x81garbage"), "not a text"),
    (
        "yaml-duplicate-key",
        lambda t, s: _raw(t, yaml.safe_dump(_small()) + "output: x.h5\noutput: y.h5\n"),
        "duplicate key 'output'",
    ),
    ("unknown-top-key", lambda t, s: _optimize_config(t, **{"optimiser.seed": 1}), "optimiser"),
    ("unknown-nested-key", lambda t, s: _optimize_config(t, **{"trajectory.harmonic": 3}), "trajectory.harmonic"),
    ("harmonics-text", lambda t, s: _optimize_config(t, **{"trajectory.harmonics": "ten"}), "trajectory.harmonics"),
    ("harmonics-zero", lambda t, s: _optimize_config(t, **{"trajectory.harmonics": 0}), "trajectory.harmonics"),
    ("harmonics-huge", lambda t, s: _optimize_config(t, **{"trajectory.harmonics": 10000}), "trajectory.harmonics"),
    (
        "frequency-inf",
        lambda t, s: _optimize_config(t, **{"trajectory.base_frequency": float("inf")}),
        "trajectory.base_frequency",
    ),
    (
        "frequency-nan",
        lambda t, s: _optimize_config(t, **{"trajectory.base_frequency": float("nan")}),
        "trajectory.base_frequency",
    ),
    (
        "frequency-negative",
        lambda t, s: _optimize_config(t, **{"trajectory.base_frequency": -1.0}),
        "trajectory.base_frequency",
    ),
    ("cost-period-zero", lambda t, s: _optimize_config(t, **{"trajectory.cost_period": 0.0}), "trajectory.cost_period"),
    ("cost-samples-one", lambda t, s: _optimize_config(t, **{"trajectory.cost_samples": 1}), "cost_samples"),
    (
        "grid-longer-than-trajectory",
        lambda t, s: _optimize_config(t, **{"trajectory.constraint_period": 100.0}),
        "constraint_period",
    ),
    (
        "robot-missing",
        lambda t, s: _raw(t, yaml.safe_dump({k: v for k, v in _small().items() if k != "robot"})),
        "robot",
    ),
    ("urdf-missing", lambda t, s: _optimize_config(t, **{"robot.urdf": "nowhere/robot.urdf"}), "robot.urdf"),
    (
        "urdf-not-xml",
        lambda t, s: (
            t.joinpath("r.urdf").write_text("this is not xml"),
            _optimize_config(t, **{"robot.urdf": str(t / "r.urdf"), "robot.source": "file"}),
        )[1],
        "robot.urdf",
    ),
    (
        "joint-unknown",
        lambda t, s: _optimize_config(t, **{"robot.active_joints": JOINTS[:5] + ["elbow"]}),
        "robot.active_joints",
    ),
    (
        "joint-twice",
        lambda t, s: _optimize_config(t, **{"robot.active_joints": JOINTS[:5] + [JOINTS[0]]}),
        "robot.active_joints",
    ),
    (
        "locked-out-of-limits",
        lambda t, s: _optimize_config(
            t, **{"robot.active_joints": JOINTS[:5], "robot.locked_joints": {JOINTS[5]: 99.0}}
        ),
        "robot.locked_joints",
    ),
    (
        "home-unknown-joint",
        lambda t, s: _optimize_config(t, **{"robot.home_posture": {"knee": 0.1}}),
        "robot.home_posture",
    ),
    ("margin-infeasible", lambda t, s: _optimize_config(t, **{"limits.position_margin": 10.0}), "limits"),
    ("velocity-negative", lambda t, s: _optimize_config(t, **{"limits.velocity": -1.0}), "limits.velocity"),
    ("acceleration-zero", lambda t, s: _optimize_config(t, **{"limits.acceleration": 0.0}), "limits.acceleration"),
    ("prior-missing", lambda t, s: _optimize_config(t, **{"sequence.prior": str(t / "none.h5")}), "sequence.prior"),
    ("prior-other-robot", lambda t, s: _optimize_config(t, **{"sequence.prior": str(s["other"])}), "sequence.prior"),
    ("prior-garbage", lambda t, s: _optimize_config(t, **{"sequence.prior": str(s["garbage"])}), "sequence.prior"),
    (
        "capsule-unknown-link",
        lambda t, s: _optimize_config(
            t,
            **{
                "constraints.self_collision": {
                    "capsules": [{"link": "nolink", "radius": 0.05, "start": [0, 0, 0], "end": [0, 0, 0.1]}]
                }
            },
        ),
        "constraints.self_collision",
    ),
    (
        "com-unknown-link",
        lambda t, s: _optimize_config(t, **{"constraints.com": {"support_links": ["nofoot"], "radius": 0.1}}),
        "constraints.com",
    ),
    ("objective-unknown", lambda t, s: _optimize_config(t, **{"optimizer.objective": "fast"}), "optimizer.objective"),
    ("config-missing", lambda t, s: ["optimize", str(t / "missing.yaml")], "not found"),
    ("seed-negative", lambda t, s: _optimize_config(t) + ["--seed", "-1"], "error: --seed: "),
    ("iterations-zero", lambda t, s: _optimize_config(t) + ["--iterations", "0"], "error: --iterations: "),
    ("workers-zero", lambda t, s: _optimize_config(t) + ["--workers", "0"], "workers"),
    ("output-is-folder", lambda t, s: _optimize_config(t)[:2] + ["-o", str(t)], "is a folder"),
    (
        "output-under-a-file",
        lambda t, s: (t.joinpath("file").write_text("x"), _optimize_config(t)[:2] + ["-o", str(t / "file" / "r.h5")])[
            1
        ],
        "is a file",
    ),
    ("resume-missing", lambda t, s: _optimize_config(t) + ["--resume"], "--resume"),
    ("verify-step-huge", lambda t, s: ["verify-gradient", _optimize_config(t)[1], "--step", "1e3"], "--step"),
    (
        "verify-objective",
        lambda t, s: ["verify-gradient", _optimize_config(t)[1], "--objective", "fast"],
        "--objective",
    ),
    (
        "verify-result-garbage",
        lambda t, s: ["verify-gradient", _optimize_config(t)[1], "--result", str(s["garbage"])],
        "--result",
    ),
    (
        "verify-result-other",
        lambda t, s: ["verify-gradient", _optimize_config(t)[1], "--result", str(s["other"])],
        "another problem",
    ),
    (
        "compare-other-robot",
        lambda t, s: ["compare-random", _optimize_config(t)[1], "--optimized", str(s["other"]), "-o", str(t / "r.h5")],
        "another problem",
    ),
    (
        "compare-pool-too-small",
        lambda t, s: [
            "compare-random",
            _optimize_config(t, **{"sequence.iterations": 1})[1],
            "--optimized",
            str(s["result"]),
            "--pool",
            "0",
            "-o",
            str(t / "r.h5"),
        ],
        "error: --pool: ",
    ),
    (
        "compare-optimized-missing",
        lambda t, s: ["compare-random", _optimize_config(t)[1], "--optimized", str(t / "no.h5"), "-o", str(t / "r.h5")],
        "--optimized",
    ),
    ("export-garbage", lambda t, s: ["export", str(s["garbage"]), "-o", str(t / "e.csv")], "garbage.h5"),
    ("export-not-result", lambda t, s: ["export", str(s["plain"]), "-o", str(t / "e.csv")], "not an excite"),
    ("export-rate-zero", lambda t, s: ["export", str(s["result"]), "--rate", "0", "-o", str(t / "e.csv")], "--rate"),
    (
        "export-iteration",
        lambda t, s: ["export", str(s["result"]), "--iteration", "9", "-o", str(t / "e.csv")],
        "--iteration",
    ),
    ("export-format", lambda t, s: ["export", str(s["result"]), "--format", "xls", "-o", str(t / "e.csv")], "--format"),
    (
        "export-periods",
        lambda t, s: ["export", str(s["result"]), "--periods", "0", "-o", str(t / "e.csv")],
        "--periods",
    ),
    ("export-missing", lambda t, s: ["export", str(t / "none.h5"), "-o", str(t / "e.csv")], "not found"),
    (
        "simulate-unknown-joint",
        lambda t, s: [
            "simulate",
            str(s["result"]),
            str(_yaml(t / "fx.yaml", {"effects": {"viscous": {"knee": 0.1}}})),
            "-o",
            str(t / "sim"),
        ],
        "effects.viscous",
    ),
    (
        "simulate-nan",
        lambda t, s: [
            "simulate",
            str(s["result"]),
            str(_yaml(t / "fx.yaml", {"effects": {"viscous": {"*": float("nan")}}})),
            "-o",
            str(t / "sim"),
        ],
        "effects",
    ),
    (
        "simulate-coefficients",
        lambda t, s: [
            "simulate",
            str(s["result"]),
            str(_yaml(t / "fx.yaml", {"effects": {"viscous": {"*": [1.0, 2.0]}}})),
            "-o",
            str(t / "sim"),
        ],
        "effects.viscous",
    ),
    (
        "simulate-not-result",
        lambda t, s: ["simulate", str(s["plain"]), str(_yaml(t / "fx.yaml", {})), "-o", str(t / "sim")],
        "not an excite",
    ),
    (
        "simulate-dir-is-file",
        lambda t, s: (
            t.joinpath("sim").write_text("x"),
            ["simulate", str(s["result"]), str(_yaml(t / "fx.yaml", {})), "-o", str(t / "sim")],
        )[1],
        "--output-dir",
    ),
    (
        "simulate-effects-malformed",
        lambda t, s: ["simulate", str(s["result"]), _raw(t, "effects: [", "fx.yaml")[1], "-o", str(t / "sim")],
        "line",
    ),
    ("identify-data-missing", lambda t, s: ["identify", str(_identify_config(t, run="none.csv"))], "none.csv"),
    ("identify-nan", lambda t, s: ["identify", str((_csv(t / "run.csv", nan_at=40), _identify_config(t))[1])], "NaN"),
    (
        "identify-empty-csv",
        lambda t, s: ["identify", str((t.joinpath("run.csv").write_text(""), _identify_config(t))[1])],
        "run.csv",
    ),
    (
        "identify-header-only",
        lambda t, s: ["identify", str((t.joinpath("run.csv").write_text("time,a,b\n"), _identify_config(t))[1])],
        "no data rows",
    ),
    (
        "identify-time-backwards",
        lambda t, s: ["identify", str((_reverse_time(_csv(t / "run.csv")), _identify_config(t))[1])],
        "increasing",
    ),
    (
        "identify-short-run",
        lambda t, s: ["identify", str((_csv(t / "run.csv", rows=20), _identify_config(t))[1])],
        "run.csv",
    ),
    (
        "identify-motionless",
        lambda t, s: ["identify", str((_csv(t / "run.csv", rows=8000, still=True), _identify_config(t))[1])],
        "excite 5 of the 36 base parameters",
    ),
    ("identify-h5-garbage", lambda t, s: ["identify", str(_identify_config(t, run=str(s["garbage"])))], "garbage.h5"),
    ("identify-result-as-data", lambda t, s: ["identify", str(_identify_config(t, run=str(s["result"])))], "ur5.h5"),
    (
        "identify-unknown-key",
        lambda t, s: ["identify", str(_identify_config(t, **{"identification.methd": "ls"}))],
        "identification.methd",
    ),
    (
        "identify-rate-above-data",
        lambda t, s: [
            "identify",
            str((_csv(t / "run.csv"), _identify_config(t, **{"preprocessing.sample_rate": 5000.0}))[1]),
        ],
        "preprocessing.sample_rate",
    ),
    (
        "identify-payload-frame",
        lambda t, s: [
            "identify",
            str(
                (
                    _csv(t / "run.csv"),
                    _identify_config(
                        t,
                        **{
                            "data.runs": [
                                {"file": "run.csv", "role": "blocks", "payload": {"mass": 1.0, "frame": "gripper"}}
                            ]
                        },
                    ),
                )[1]
            ),
        ],
        "data.runs[0].payload.frame",
    ),
    (
        "identify-payload-mass",
        lambda t, s: [
            "identify",
            str(_identify_config(t, **{"data.runs": [{"file": "run.csv", "payload": {"mass": 0.0}}]})),
        ],
        "payload.mass",
    ),
    (
        "identify-held-velocity",
        lambda t, s: ["identify", str(_identify_config(t, **{"identification.held_velocity": [0.1, -0.2]}))],
        "identification.held_velocity",
    ),
    (
        "identify-folds",
        lambda t, s: ["identify", str(_identify_config(t, **{"identification.folds": 2}))],
        "identification.folds",
    ),
    (
        "identify-candidate",
        lambda t, s: ["identify", str(_identify_config(t, **{"identification.candidates": ["coulomb", "lugre"]}))],
        "identification.candidates",
    ),
    ("validate-report-missing", lambda t, s: ["validate", str(t / "none.h5"), str(_identify_config(t))], "not found"),
    ("validate-not-report", lambda t, s: ["validate", str(s["result"]), str(_identify_config(t))], "identify report"),
]


def _reverse_time(path):
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    table[100:110, 0] = table[100, 0]
    header = path.read_text().splitlines()[0]
    np.savetxt(path, table, delimiter=",", header=header, comments="", fmt="%.10g")
    return path


@pytest.mark.parametrize("case, build, expected", CASES, ids=[c[0] for c in CASES])
def test_bad_input_gives_one_line_and_no_file(case, build, expected, shared, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = build(tmp_path, shared)
    protected = {k: v.read_bytes() for k, v in shared.items()}
    assert_refused(tmp_path, argv, expected)
    assert {k: v.read_bytes() for k, v in shared.items()} == protected
