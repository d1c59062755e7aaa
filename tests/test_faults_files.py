"""Faults of the machine and of the files a user gives (issue 20): a full disk, problems with no
motion in them, numbers without bounds, hostile YAML, HDF5, NPZ and CSV files, two runs on one
output. A bad case exits with status 2 and one line naming the field or file, prints no traceback
and leaves no file behind or changed; each runs under a timeout."""

import os
import resource
import shutil
import subprocess
import sys
from contextlib import chdir
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io
import yaml
from conftest import assert_refused, pendulum_config, tcp_server
from numpy.lib import recfunctions as rf
from rosbags.rosbag2 import Writer
from rosbags.typesys import Stores, get_typestore
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.config_file import load_problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.measured.files import read_table
from excite_cli.storage.paths import output_lock

runner = CliRunner()
EXCITE = Path(sys.executable).with_name("excite")
EFFECTS = {"sample_rate": 100.0, "periods": 1, "torque_noise": 0.01, "seed": 1, "effects": {"viscous": {"*": 0.2}}}


@pytest.fixture(scope="module")
def pendulum_run(tmp_path_factory) -> Path:
    """A folder with a two-iteration pendulum result ``out.h5``, its simulated runs ``sim/run_k.csv``
    and an identify config ``id.yaml`` of them."""
    folder = tmp_path_factory.mktemp("pendulum")
    config = pendulum_config(folder, iterations=2)
    assert runner.invoke(app, ["optimize", str(config)]).exit_code == 0
    (folder / "effects.yaml").write_text(yaml.safe_dump(EFFECTS))
    argv = ["simulate", str(folder / "out.h5"), str(folder / "effects.yaml"), "-o", str(folder / "sim")]
    assert runner.invoke(app, argv).exit_code == 0
    identify = {
        "robot": {"urdf": "pendulum.urdf", "active_joints": ["hinge"]},
        "data": {
            "runs": [{"file": "sim/run_1.csv", "role": "fit"}, {"file": "sim/run_2.csv", "role": "validation"}],
            "columns": {"q": ["q_hinge"], "tau": ["tau_hinge"]},
        },
    }
    (folder / "id.yaml").write_text(yaml.safe_dump(identify))
    return folder


def _copy(source: Path, folder: Path) -> Path:
    """``source``'s files copied into ``folder`` (the commands run on the copy)."""
    shutil.copytree(source, folder, dirs_exist_ok=True)
    return folder


def _run(argv: list[str], cwd: Path, file_size: int | None = None, timeout: float = 240) -> subprocess.CompletedProcess:
    """``excite argv`` in a process of its own, its files limited to ``file_size`` bytes (a full disk)."""

    def limit() -> None:
        if file_size is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (file_size, file_size))

    return subprocess.run(
        [str(EXCITE), *argv], cwd=cwd, preexec_fn=limit, capture_output=True, text=True, timeout=timeout
    )


def _one_error_line(process: subprocess.CompletedProcess, expected: str, status: int = 2) -> None:
    assert process.returncode == status, process.stderr
    assert "Traceback" not in process.stderr + process.stdout
    errors = [line for line in process.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and expected in errors[0], process.stderr


# --- a full disk (RLIMIT_FSIZE: every write beyond the limit fails with EFBIG) -----------------------

DISK_FULL = {
    "optimize": (["optimize", "pendulum.yaml", "-o", "new/result.h5"], "new/result.h5"),
    "identify": (["identify", "id.yaml", "-o", "new/report.h5"], "new/report.h5"),
    "simulate": (["simulate", "out.h5", "effects.yaml", "-o", "new/sim"], "new/sim/run_1.csv"),
    "export": (["export", "out.h5", "-o", "new/play.csv"], "new/play.csv"),
    "compare-random": (
        ["compare-random", "pendulum.yaml", "--optimized", "out.h5", "--pool", "4", "-o", "new/random.h5"],
        "new/random.h5",
    ),
}


@pytest.mark.parametrize("command", list(DISK_FULL))
def test_a_full_disk_is_one_line_and_leaves_nothing(pendulum_run, tmp_path, command):
    folder = _copy(pendulum_run, tmp_path / "run")
    argv, written = DISK_FULL[command]
    before = sorted(p.relative_to(folder) for p in folder.rglob("*"))
    process = _run(argv, folder, file_size=2000)
    _one_error_line(process, f"cannot write {written}: File too large")
    assert "finished iteration" not in process.stderr  # nothing finished is on disk, so none is said to be kept
    assert sorted(p.relative_to(folder) for p in folder.rglob("*")) == before  # no file, no .partial, no folder


def test_a_disk_that_fills_up_at_the_second_iteration_says_what_is_on_disk(pendulum_run, tmp_path):
    """Room for the first iteration's file, not the second's: the message counts the file's iterations."""
    folder = _copy(pendulum_run, tmp_path / "run")
    process = _run(
        ["optimize", "pendulum.yaml", "-o", "again.h5"], folder, file_size=(folder / "out.h5").stat().st_size - 1
    )
    _one_error_line(process, "cannot write again.h5: File too large; kept 1 finished iteration(s) in again.h5")
    with h5py.File(folder / "again.h5") as f:
        assert list(f["iterations"]) == ["1"]


def test_a_disk_that_fills_up_at_the_plots_keeps_the_result(pendulum_run, tmp_path):
    folder = _copy(pendulum_run, tmp_path / "run")
    result = folder / "out.h5"
    process = _run(["optimize", "pendulum.yaml", "-o", "again.h5"], folder, file_size=result.stat().st_size + 4096)
    _one_error_line(process, "cannot write again_trajectories.png: File too large")
    with h5py.File(folder / "again.h5") as f:
        assert len(f["iterations"]) == 2
    assert not [p.name for p in folder.iterdir() if p.name.startswith("again_") or p.name.endswith(".partial")]


# --- problems with no motion in them ---------------------------------------------------------------


@pytest.mark.parametrize(
    "changes, expected",
    [
        ({"trajectory.base_frequency": 1e-9}, "less than a quarter of its base period"),
        ({"trajectory.base_frequency": 1e6}, "fewer than 4 constraint-grid instants per cycle"),
        ({"trajectory.constraint_period": 2.0}, "fewer than 4 constraint-grid instants per cycle"),
    ],
    ids=["frequency-1e-9", "frequency-1e6", "coarse-grid"],
)
def test_a_frequency_with_no_motion_is_refused_before_the_run(tmp_path, changes, expected):
    config = pendulum_config(tmp_path, changes={"trajectory.harmonics": 5, **changes})
    assert_refused(tmp_path, ["optimize", str(config)], expected)


def test_limits_that_leave_no_motion_end_in_a_warning_and_status_1(tmp_path):
    """An acceleration limit of 1e-9 rad/s²: the optimizer returns a trajectory that barely moves.
    It is kept (the user may look at it) but the run says so and fails."""
    config = pendulum_config(tmp_path, changes={"limits.acceleration": 1e-9, "limits.velocity": 1e-9})
    result = runner.invoke(app, ["optimize", str(config)])
    assert result.exit_code == 1, result.output
    assert "warning: cond(C)" in result.output and "do not excite every base parameter" in result.output
    with h5py.File(tmp_path / "out.h5") as f:
        assert f["iterations/1"].attrs["cond_stacked"] > 1e6


def test_a_well_posed_pendulum_passes_the_excitation_check(pendulum_run):
    with h5py.File(pendulum_run / "out.h5") as f:
        assert f["iterations/2"].attrs["cond_stacked"] < 1e3


# --- numbers without bounds ------------------------------------------------------------------------

BOUNDS = [
    ("max-iterations", {"optimizer.max_iterations": 10**12}, "optimizer.max_iterations"),
    ("seed-huge", {"optimizer.seed": 2**70}, "optimizer.seed"),
    ("restarts", {"optimizer.restarts": 10**9}, "optimizer.restarts"),
    ("starts", {"optimizer.starts": 10**9}, "optimizer.starts"),
    ("screen-iterations", {"optimizer.screen_iterations": 10**9}, "optimizer.screen_iterations"),
    ("workers-config", {"optimizer.workers": 100000}, "optimizer.workers"),
    ("check-refinement", {"limits.check_refinement": 10**9}, "limits.check_refinement"),
    ("fine-grid", {"limits.check_refinement": 1000, "trajectory.constraint_period": 0.001}, "its fine check"),
    ("iterations", {"sequence.iterations": 10**9}, "sequence.iterations"),
    ("pool-size", {"random_baseline.pool_size": 10**12}, "random_baseline.pool_size"),
    ("baseline-seed", {"random_baseline.seed": 2**64}, "random_baseline.seed"),
    ("scheduler-garbage", {"optimizer.scheduler": "garbage"}, "expected a Dask scheduler address"),
    ("scheduler-no-port", {"optimizer.scheduler": "tcp://"}, "optimizer.scheduler"),
]


@pytest.mark.parametrize("changes, expected", [c[1:] for c in BOUNDS], ids=[c[0] for c in BOUNDS])
def test_a_number_beyond_its_bound_is_refused_by_name(tmp_path, changes, expected):
    config = pendulum_config(tmp_path, changes=changes)
    assert_refused(tmp_path, ["optimize", str(config)], expected)


def test_a_scheduler_that_is_a_web_server_is_one_line(tmp_path):
    """Dask's client read the server's first bytes as a message length: MemoryError (3.07 EiB)."""
    with tcp_server(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n") as address:
        argv = ["optimize", str(pendulum_config(tmp_path)), "--scheduler", address]
        assert_refused(tmp_path, argv, f"--scheduler: the server at {address} is not a Dask scheduler")


def test_a_scheduler_without_the_cluster_extra_is_one_line(tmp_path, monkeypatch):
    """distributed is the ``cluster`` extra: a plain ``pip install`` runs locally, and a scheduler
    asked for without it is one line, before anything is computed or written."""
    import excite_cli.search.scheduler as scheduler_module

    real = scheduler_module.find_spec
    monkeypatch.setattr(scheduler_module, "find_spec", lambda name: None if name == "distributed" else real(name))
    argv = ["optimize", str(pendulum_config(tmp_path)), "--scheduler", "tcp://127.0.0.1:8786"]
    assert_refused(
        tmp_path,
        argv,
        "--scheduler: needs Dask's distributed package, which is not installed; "
        "expected the cluster extra: pip install 'excite[cluster]'",
    )


@pytest.mark.parametrize(
    "command, option",
    [
        ("optimize", ["--workers", "100000"]),
        ("optimize", ["--seed", str(2**70)]),
        ("optimize", ["--scheduler", "::::"]),
        ("compare-random", ["--pool", str(10**12)]),
        ("verify-gradient", ["--seed", str(2**70)]),
    ],
)
def test_a_command_line_number_beyond_its_bound_is_refused_by_name(tmp_path, command, option):
    assert_refused(tmp_path, [command, str(pendulum_config(tmp_path)), *option], option[0].lstrip("-"))


def test_an_export_rate_below_the_motion_is_refused_by_name(pendulum_run, tmp_path):
    folder = _copy(pendulum_run, tmp_path / "run")
    assert_refused(folder, ["export", str(folder / "out.h5"), "--rate", "1e-9"], "cannot represent the trajectory")


SIMULATION_BOUNDS = [
    ("rate", {"sample_rate": 1e12}, "sample_rate"),
    ("rate-below-the-motion", {"sample_rate": 1e-9}, "sample_rate: 1e-09 Hz cannot represent the trajectory"),
    ("periods", {"periods": 10**9}, "periods"),
    ("samples", {"periods": 1000, "sample_rate": 90000.0}, "samples per run"),
    ("seed", {"seed": 2**70}, "seed"),
]


@pytest.mark.parametrize("changes, expected", [c[1:] for c in SIMULATION_BOUNDS], ids=[c[0] for c in SIMULATION_BOUNDS])
def test_a_simulation_beyond_its_bounds_is_refused_by_name(pendulum_run, tmp_path, changes, expected):
    (tmp_path / "effects.yaml").write_text(yaml.safe_dump({**EFFECTS, **changes}))
    argv = ["simulate", str(pendulum_run / "out.h5"), str(tmp_path / "effects.yaml"), "-o", str(tmp_path / "sim")]
    assert_refused(tmp_path, argv, expected)


IDENTIFY_FIELDS = [
    ("zero-torque-constant", {"data": {"torque_constants": [0.0]}}, "data.torque_constants"),
    ("infinite-torque-constant", {"data": {"torque_constants": [float("inf")]}}, "data.torque_constants"),
    # issue 62: 1e-300 Nm/A ended in 'the SDP ended infeasible', a ratio of 1e300 in numpy overflow warnings
    ("tiny-torque-constant", {"data": {"torque_constants": [1e-300]}}, "another unit?"),
    ("huge-gear-ratio", {"data": {"transmission": {"gear_ratios": [1e300]}}}, "another unit?"),
    ("time-true", {"data": {"columns": {"time": True, "q": ["q_hinge"], "tau": ["tau_hinge"]}}}, "data.columns.time"),
    ("zero-sign", {"data": {"signs": [0.0]}}, "every sign must be 1 or -1"),
    ("blocks", {"data": {"validation_blocks": 10**9}}, "data.validation_blocks"),
    ("rate", {"preprocessing": {"sample_rate": 1e12}}, "preprocessing.sample_rate"),
    (
        "payload-not-a-body",
        {"data": {"runs": [{"file": "sim/run_1.csv", "payload": {"mass": 1.0, "inertia": [1, 0, 1, 0, 0, -1]}}]}},
        "no body has principal moments",
    ),
    (
        "payload-triangle",
        {"data": {"runs": [{"file": "sim/run_1.csv", "payload": {"mass": 1.0, "inertia": [1, 0, 1, 0, 0, 3]}}]}},
        "each at most the sum of the other two",
    ),
    # the coupled candidates acted on the wrong joints (accepted when the data are joint-side)
    ("gear-ratios", {"data": {"transmission": {"gear_ratios": [100.0, 50.0]}}}, "gear_ratios: 2 values for 1 active"),
    ("signs", {"data": {"signs": [1.0, -1.0]}}, "data.signs: 2 values for 1 active joint"),
    (
        "rate-1e300",  # was refused with a 300-digit sample count and no field name
        {"data": {"sample_rate": 1e300, "columns": {"time": None, "q": ["q_hinge"], "tau": ["tau_hinge"]}}},
        "data.sample_rate: Input should be less than or equal to 100000",
    ),
]


@pytest.mark.parametrize("changes, expected", [c[1:] for c in IDENTIFY_FIELDS], ids=[c[0] for c in IDENTIFY_FIELDS])
def test_an_identify_field_no_robot_can_have_is_refused_by_name(pendulum_run, tmp_path, changes, expected):
    folder = _copy(pendulum_run, tmp_path / "run")
    config = yaml.safe_load((folder / "id.yaml").read_text())
    for section, values in changes.items():
        config[section] = {**config.get(section, {}), **values}
    (folder / "id.yaml").write_text(yaml.safe_dump(config))
    assert_refused(folder, ["identify", str(folder / "id.yaml"), "-o", str(folder / "report.h5")], expected)


# --- hostile or odd YAML ----------------------------------------------------------------------------

BOMB = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{b}: &{b} [{', '.join([f'*{a}'] * 10)}]\n" for a, b in zip("abcdefg", "bcdefgh")
)


@pytest.mark.parametrize(
    "text, expected",
    [
        (BOMB, "its aliases expand to more than 1,000,000 values"),
        ("robot: &r [*r]\n", "its aliases expand to more than"),
        ("a: " + "[" * 20000 + "]" * 20000 + "\n", "nested more than 64 levels deep"),
        ("a:\n" + "".join("  " * k + "b:\n" for k in range(1, 200)), "nested more than 64 levels deep"),
        ("robot: 1\nrobot: 2\n", "duplicate key 'robot'"),
        ("robot: !!python/object/apply:os.system ['true']\n", "malformed YAML"),
        ("robot:\n  urdf: a\x00b\n", "malformed YAML at line 2, column 10: character #x0000 is not allowed"),
    ],
    ids=["alias-bomb", "recursive-alias", "deep-flow", "deep-block", "duplicate-key", "python-tag", "nul-byte"],
)
@pytest.mark.parametrize("command", ["optimize", "identify", "simulate"])
def test_a_hostile_yaml_file_is_one_short_line(pendulum_run, tmp_path, command, text, expected):
    (tmp_path / "bad.yaml").write_text(text)
    argv = {
        "optimize": ["optimize", str(tmp_path / "bad.yaml")],
        "identify": ["identify", str(tmp_path / "bad.yaml")],
        "simulate": ["simulate", str(pendulum_run / "out.h5"), str(tmp_path / "bad.yaml"), "-o", str(tmp_path / "s")],
    }[command]
    assert_refused(tmp_path, argv, expected)
    assert len(runner.invoke(app, argv).output) < 500


def test_a_yaml_file_bigger_than_a_config_is_refused(tmp_path):
    (tmp_path / "big.yaml").write_text("# " + "x" * 11_000_000 + "\n")
    assert_refused(tmp_path, ["optimize", str(tmp_path / "big.yaml")], "larger than 10 MB")


def test_yaml_merge_keys_are_accepted_and_an_explicit_key_wins(pendulum_run):
    """``<<: *run`` (YAML 1.1 merge keys) was refused as malformed: runs sharing a payload, capsules
    sharing a radius are written this way."""
    text = (pendulum_run / "id.yaml").read_text()
    data = yaml.safe_load(text)
    data["data"]["runs"] = "RUNS"
    runs = (
        "\n    - &fit {file: sim/run_1.csv, role: fit, payload: {mass: 0.5}}"
        "\n    - {<<: *fit, file: sim/run_2.csv, role: validation}"
    )
    merged = yaml.safe_dump(data).replace(" RUNS", runs)
    path = pendulum_run / "merged.yaml"
    path.write_text(merged)
    try:
        problem = load_problem(path, IdentifyProblem)
    finally:
        path.unlink()
    second = problem.data.runs[1]
    assert (second.file, second.role, second.payload.mass) == ("sim/run_2.csv", "validation", 0.5)


def test_a_key_given_twice_beside_a_merge_is_still_refused(tmp_path):
    (tmp_path / "twice.yaml").write_text("base: &b {x: 1}\nrobot: {<<: *b, urdf: a, urdf: b}\n")
    assert_refused(tmp_path, ["optimize", str(tmp_path / "twice.yaml")], "duplicate key 'urdf'")


# --- hostile or odd data files ----------------------------------------------------------------------


def _identify_on(folder: Path, data_file: str) -> list[str]:
    config = yaml.safe_load((folder / "id.yaml").read_text())
    config["data"]["runs"] = [{"file": data_file}]
    (folder / "odd.yaml").write_text(yaml.safe_dump(config))
    return ["identify", str(folder / "odd.yaml"), "-o", str(folder / "report.h5")]


def _columns(folder: Path) -> dict[str, np.ndarray]:
    table = np.loadtxt(folder / "sim" / "run_1.csv", delimiter=",", skiprows=1)
    return {"time": table[:, 0], "q_hinge": table[:, 1], "tau_hinge": table[:, 2]}


def _write_h5(path: Path, arrays: dict[str, np.ndarray], links: dict[str, h5py.SoftLink | h5py.ExternalLink]) -> None:
    with h5py.File(path, "w") as f:
        for name, values in {**arrays, **links}.items():
            f[name] = values


def test_links_in_an_hdf5_data_file_that_lead_nowhere_are_left_out(pendulum_run, tmp_path):
    """A soft-link loop and an external link to a missing file (a traceback before); links to other
    files are never followed."""
    links = {"a": h5py.SoftLink("/b"), "b": h5py.SoftLink("/a"), "x": h5py.ExternalLink("missing.h5", "/d")}
    _write_h5(tmp_path / "data.h5", _columns(pendulum_run), links)
    assert sorted(read_table(tmp_path / "data.h5").names) == ["q_hinge", "tau_hinge", "time"]


def test_a_column_that_is_an_external_link_is_named_as_one(pendulum_run, tmp_path):
    folder = _copy(pendulum_run, tmp_path / "run")
    columns = _columns(pendulum_run)
    _write_h5(folder / "times.h5", {"t": columns["time"]}, {})
    del columns["time"]
    _write_h5(folder / "data.h5", columns, {"time": h5py.ExternalLink("times.h5", "/t")})
    assert_refused(
        folder, _identify_on(folder, "data.h5"), "'time' is a link to times.h5:/t, which excite does not follow"
    )


@pytest.mark.parametrize("suffix", [".h5", ".npz"])
def test_a_data_file_of_empty_arrays_is_refused(pendulum_run, tmp_path, suffix):
    folder = _copy(pendulum_run, tmp_path / "run")
    empty = {name: np.zeros(0) for name in ("time", "q_hinge", "tau_hinge")}
    if suffix == ".h5":
        _write_h5(folder / "empty.h5", empty, {})
    else:
        np.savez(folder / "empty.npz", **empty)
    assert_refused(folder, _identify_on(folder, f"empty{suffix}"), f"empty{suffix} has no data rows")


def test_a_data_file_of_one_row_is_refused(pendulum_run, tmp_path):
    folder = _copy(pendulum_run, tmp_path / "run")
    (folder / "one.csv").write_text("time,q_hinge,tau_hinge\n0,0.1,0.2\n")
    assert_refused(folder, _identify_on(folder, "one.csv"), "one.csv has fewer than 2 usable rows")


def test_a_2_gb_sparse_csv_is_refused_at_once(pendulum_run, tmp_path):
    folder = _copy(pendulum_run, tmp_path / "run")
    with open(folder / "sparse.csv", "wb") as f:
        f.truncate(2 * 1024**3)
    assert_refused(folder, _identify_on(folder, "sparse.csv"), "larger than 1 GB of text")


def test_a_csv_of_nul_bytes_is_refused(pendulum_run, tmp_path):
    folder = _copy(pendulum_run, tmp_path / "run")
    with open(folder / "zeros.csv", "wb") as f:
        f.truncate(50_000_000)
    assert_refused(folder, _identify_on(folder, "zeros.csv"), "holds NUL bytes")


@pytest.mark.parametrize("damage", ["header-kept-rest-zero", "header-kept-rest-random"])
def test_a_corrupt_mat_file_is_one_line(pendulum_run, tmp_path, damage):
    """scipy.io raises TypeError on these (a 135-line traceback)."""
    folder = _copy(pendulum_run, tmp_path / "run")
    scipy.io.savemat(folder / "run.mat", _columns(folder), format="5" if damage.endswith("random") else "4")
    raw = (folder / "run.mat").read_bytes()
    rest = bytes(len(raw) - 128) if damage.endswith("zero") else np.random.default_rng(0).bytes(len(raw) - 128)
    (folder / "run.mat").write_bytes(raw[:128] + rest)
    assert_refused(folder, _identify_on(folder, "run.mat"), "cannot read run.mat as MAT")


# --- a run recorded in several files: paired by time stamp, sorted, cut only with a warning --------


def _split_run(folder: Path, tau_rows: slice = slice(None), tau_order: int = 1, repeat: bool = False) -> list[str]:
    """sim/run_1.csv as two files, ``q.csv`` and ``tau.csv`` (its rows ``tau_rows``, in time order
    or reversed, a stamp repeated), and the identify argv of a run of both, time blocks alternating."""
    columns = _columns(folder)
    time, q, tau = columns["time"], columns["q_hinge"], columns["tau_hinge"]
    np.savetxt(folder / "q.csv", np.column_stack([time, q]), delimiter=",", header="time,q", comments="")
    stamps = time.copy()
    if repeat:
        stamps[5] = stamps[4]
    rows = np.column_stack([stamps, tau])[tau_rows][::tau_order]
    np.savetxt(folder / "tau.csv", rows, delimiter=",", header="time,tau", comments="")
    config = yaml.safe_load((folder / "id.yaml").read_text())
    config["data"]["runs"] = [{"file": ["q.csv", "tau.csv"]}]
    config["data"]["columns"] = {"time": "time", "q": ["q/q"], "tau": ["tau/tau"]}
    (folder / "split.yaml").write_text(yaml.safe_dump(config))
    return ["identify", str(folder / "split.yaml"), "-o", str(folder / "report.h5"), "--force"]


def _validation_error(folder: Path) -> np.ndarray:
    """(n,) the report's relative validation error per joint [%]."""
    with h5py.File(folder / "report.h5") as f:
        return f["identification/relative_after"][()]


def test_a_file_of_a_run_in_descending_time_is_paired_by_stamp(pendulum_run, tmp_path):
    """Paired by position, the reversed torques gave 58-120 % validation error, exit 0."""
    folder = _copy(pendulum_run, tmp_path / "run")
    assert runner.invoke(app, _split_run(folder)).exit_code == 0
    in_order = _validation_error(folder)
    assert runner.invoke(app, _split_run(folder, tau_order=-1)).exit_code == 0
    np.testing.assert_allclose(_validation_error(folder), in_order, rtol=1e-9)
    assert in_order.max() < 1.0  # [%]


def test_a_time_stamp_given_twice_in_a_file_of_a_run_is_one_line(pendulum_run, tmp_path):
    folder = _copy(pendulum_run, tmp_path / "run")
    assert_refused(folder, _split_run(folder, repeat=True), "tau.csv has two rows at time 0.04 s (lines 6 and 7)")


def test_a_file_that_covers_part_of_a_run_cuts_it_with_a_warning_naming_the_seconds(pendulum_run, tmp_path):
    folder = _copy(pendulum_run, tmp_path / "run")
    result = runner.invoke(app, _split_run(folder, tau_rows=slice(0, 801)), env={"COLUMNS": "400"})
    assert result.exit_code == 0, result.output
    assert "warning: the run of q.csv + tau.csv is cut to the span every file covers: q.csv loses 2 s" in result.output


def test_a_fifo_given_as_a_data_file_is_refused_at_once(pendulum_run, tmp_path):
    folder = _copy(pendulum_run, tmp_path / "run")
    os.mkfifo(folder / "pipe.csv")  # nobody writes: opening it to read would wait for ever
    process = _run(_identify_on(folder, "pipe.csv"), folder, timeout=60)  # a hang fails by the timeout
    _one_error_line(process, "pipe.csv is a FIFO, not a regular file")


# --- damaged results and reports ---------------------------------------------------------------------


def _loop(f):
    del f["iterations/1/alpha"]
    f["iterations/1/alpha"], f["x"] = h5py.SoftLink("/x"), h5py.SoftLink("/iterations/1/alpha")


def _external(f):
    del f["iterations"]
    f["iterations"] = h5py.ExternalLink("missing.h5", "/iterations")


def _empty(f):
    del f["iterations/1/alpha"]
    f["iterations/1/alpha"] = np.zeros(0)


def _not_a_config(f):
    f.attrs["config"] = "- a list\n- not a config\n"


def _bomb(f):
    f.attrs["config"] = BOMB


def _text_where_a_number_belongs(f):
    f["iterations/1"].attrs["wall_time_s"] = "soon"


DAMAGE = {
    "link-loop": (_loop, "is damaged or not an excite file"),
    "external-link": (_external, "is damaged or not an excite file"),
    "empty-alpha": (_empty, ""),
    "config-a-list": (_not_a_config, "config"),
    "config-alias-bomb": (_bomb, ""),
    "text-for-a-number": (_text_where_a_number_belongs, ""),
}
DAMAGED_USE = {
    "simulate": lambda d: ["simulate", str(d / "bad.h5"), str(d / "effects.yaml"), "-o", str(d / "sim2")],
    "export": lambda d: ["export", str(d / "bad.h5"), "-o", str(d / "play.csv")],
    "resume": lambda d: ["optimize", str(d / "pendulum.yaml"), "-o", str(d / "bad.h5"), "--resume"],
}


@pytest.mark.parametrize("damage", list(DAMAGE))
@pytest.mark.parametrize("use", list(DAMAGED_USE))
def test_a_damaged_result_is_one_line(pendulum_run, tmp_path, damage, use):
    folder = _copy(pendulum_run, tmp_path / "run")
    shutil.copy(folder / "out.h5", folder / "bad.h5")
    change, expected = DAMAGE[damage]
    with h5py.File(folder / "bad.h5", "a") as f:
        change(f)
    if use in ("simulate", "export") and damage == "text-for-a-number":
        assert runner.invoke(app, DAMAGED_USE[use](folder)).exit_code == 0  # they do not read wall times
        return
    assert_refused(folder, DAMAGED_USE[use](folder), expected or "bad.h5")


def test_a_damaged_report_is_one_line(pendulum_run, tmp_path):
    with h5py.File(tmp_path / "report.h5", "w") as f:
        f["identification/effects"] = h5py.SoftLink("/identification/effects")
    argv = ["validate", str(tmp_path / "report.h5"), str(pendulum_run / "id.yaml")]
    assert_refused(tmp_path, argv, "is damaged or not an excite file")


def _replace(f, name, change):
    values = f[name][()]
    del f[name]
    f[name] = change(values)


def _nan_values(rows):
    assert len(rows), "the report has effects to damage"
    for field in ("value", "value_consistent"):
        rows[field] = np.nan
    return rows


REPORT_DAMAGE = {
    "cutoff": (lambda f: f["identification"].attrs.__setitem__("cutoff_Hz", np.nan), "cutoff_Hz is nan"),
    "base-short": (
        lambda f: _replace(f, "identification/base_parameters", lambda b: b[:1]),
        "/identification/base_parameters has shape 1; expected",
    ),
    "base-nan": (
        lambda f: _replace(f, "identification/base_parameters", lambda b: b * np.nan),
        "/identification/base_parameters holds NaN or infinite values",
    ),
    "effect-values-nan": (
        lambda f: _replace(f, "identification/effects", _nan_values),
        "/identification/effects holds NaN or infinite values",
    ),
    "no-effect-field": (
        lambda f: _replace(f, "identification/effects", lambda r: rf.drop_fields(r, "effect", usemask=False)),
        "/identification/effects has no field 'effect'",
    ),
    "coupling-shape": (
        lambda f: _replace(f, "identification/effect_coupling", lambda c: np.zeros((len(c) + 1, 3))),
        "/identification/effect_coupling has shape",
    ),
    "range-nan": (
        lambda f: _replace(f, "identification/fit_q_range", lambda r: r * np.nan),
        "/identification/fit_q_range holds NaN",
    ),
}


@pytest.fixture(scope="module")
def pendulum_report(pendulum_run, tmp_path_factory):
    folder = _copy(pendulum_run, tmp_path_factory.mktemp("report") / "run")
    assert runner.invoke(app, ["identify", str(folder / "id.yaml"), "-o", str(folder / "report.h5")]).exit_code == 0
    return folder


@pytest.mark.parametrize("damage", list(REPORT_DAMAGE))
def test_a_report_with_a_field_damaged_is_one_line_naming_it(pendulum_report, tmp_path, damage):
    """``validate`` reads every field of the model it uses checked: shape from the report's own joints
    and base parameters, finite values (a NaN effect value printed a table of nan before)."""
    folder = _copy(pendulum_report, tmp_path / "run")
    change, expected = REPORT_DAMAGE[damage]
    with h5py.File(folder / "report.h5", "a") as f:
        change(f)
    argv = ["validate", str(folder / "report.h5"), str(folder / "id.yaml")]
    assert_refused(folder, argv, expected)


# --- two runs, one output ----------------------------------------------------------------------------


@pytest.mark.parametrize("command", ["optimize", "identify"])
def test_an_output_another_run_is_writing_is_refused(pendulum_run, tmp_path, command):
    folder = _copy(pendulum_run, tmp_path / "run")
    config = "pendulum.yaml" if command == "optimize" else "id.yaml"
    with output_lock(folder / "busy.h5", "output"):
        argv = [command, str(folder / config), "-o", str(folder / "busy.h5"), "--force"]
        assert_refused(folder, argv, f"is being written by another excite run (process {os.getpid()})")
    assert not (folder / ".busy.h5.lock").exists()


def test_a_lock_left_by_a_killed_run_is_taken_over(pendulum_run, tmp_path):
    folder = _copy(pendulum_run, tmp_path / "run")
    (folder / ".again.h5.lock").write_text("99999999\n")  # no process holds it
    assert (
        runner.invoke(app, ["optimize", str(folder / "pendulum.yaml"), "-o", str(folder / "again.h5")]).exit_code == 0
    )
    assert (folder / "again.h5").is_file() and not (folder / ".again.h5.lock").exists()


# --- every input file through one opener, every message in one style ---------------------------------

#: Each file a command reads, as (argv with {} for the file, where the line names it).
INPUTS = {
    "optimize-CONFIG": (["optimize", "{}"], "CONFIG"),
    "identify-CONFIG": (["identify", "{}"], "CONFIG"),
    "export-RESULT": (["export", "{}"], "RESULT"),
    "view-RESULT": (["view", "{}"], "RESULT"),
    "validate-REPORT": (["validate", "{}", "id.yaml"], "REPORT"),
    "validate-CONFIG": (["validate", "out.h5", "{}"], "CONFIG"),
    "simulate-RESULT": (["simulate", "{}", "effects.yaml"], "RESULT"),
    "simulate-EFFECTS": (["simulate", "out.h5", "{}"], "EFFECTS"),
    "compare-random--optimized": (["compare-random", "pendulum.yaml", "--optimized", "{}"], "--optimized"),
    "verify-gradient--result": (["verify-gradient", "pendulum.yaml", "--result", "{}"], "--result"),
    "robot.urdf": (["optimize", "urdf.yaml"], "urdf.yaml: robot.urdf"),
    "sequence.prior": (["optimize", "prior.yaml"], "prior.yaml: sequence.prior"),
}


def _in(folder: Path, argv: list[str]) -> list[str]:
    """``argv`` with the names of files in ``folder`` made absolute (the commands run in this process)."""
    return [str(folder / a) if (folder / a).exists() else a for a in argv]


@pytest.mark.timeout(60)  # a read that blocks fails this case, not the suite
@pytest.mark.parametrize("kind", ["folder", "fifo"])
@pytest.mark.parametrize("given", list(INPUTS))
def test_an_input_that_is_not_a_regular_file_is_named_at_once(pendulum_run, tmp_path, given, kind):
    """A folder or a FIFO (which nobody writes: reading it would wait for ever) given as any input
    file: one line naming the argument or config field as the command spells it, at once."""
    folder = _copy(pendulum_run, tmp_path / "run")
    odd = folder / "odd.h5"
    odd.mkdir() if kind == "folder" else os.mkfifo(odd)
    config = {**yaml.safe_load((folder / "pendulum.yaml").read_text()), "output": "new.h5"}
    (folder / "urdf.yaml").write_text(yaml.safe_dump({**config, "robot": {**config["robot"], "urdf": "odd.h5"}}))
    (folder / "prior.yaml").write_text(yaml.safe_dump({**config, "sequence": {"iterations": 1, "prior": "odd.h5"}}))
    argv, where = INPUTS[given]
    what = "is a folder" if kind == "folder" else "is a FIFO, not a regular file"
    line = assert_refused(folder, _in(folder, [a.format("odd.h5") for a in argv]), f"odd.h5 {what}")
    assert line.startswith(f"error: {where}: ") or f"/{where}: " in line, line


@pytest.mark.parametrize(
    "argv, head",
    [
        (["optimize", "pendulum.yaml", "--iterations", "0"], "error: --iterations: "),
        (["optimize", "pendulum.yaml", "--workers", "0"], "error: --workers: "),
        (["compare-random", "pendulum.yaml", "--seed", "-1"], "error: --seed: "),
        (["identify", "id.yaml", "--fit", "bogus"], "error: --fit: "),
        (["simulate", "out.h5", "missing.yaml"], "error: EFFECTS: effects file not found: missing.yaml"),
        (["identify", "missing_run.yaml"], "error: {folder}/missing_run.yaml: data.runs: file not found: "),
    ],
    ids=["override-iterations", "override-workers", "override-seed", "override-fit", "effects-file", "runtime-field"],
)
def test_every_message_names_what_the_user_typed(pendulum_run, tmp_path, argv, head):
    """One style: an argument as the command spells it, an option that overrode a config field by its
    flag (it said 'command line: sequence.iterations'), a config field after its file, including
    those found while the run reads its data (they named no file); the effects file is EFFECTS."""
    folder = _copy(pendulum_run, tmp_path / "run")
    config = yaml.safe_load((folder / "id.yaml").read_text())
    config["data"]["runs"][0]["file"] = "sim/run_9.csv"
    (folder / "missing_run.yaml").write_text(yaml.safe_dump(config))
    line = assert_refused(folder, _in(folder, argv), "")
    assert line.startswith(head.format(folder=folder)), line


def test_a_killed_runs_lock_and_partial_file_are_removed_with_a_line_each(pendulum_run, tmp_path):
    """SIGKILL leaves the hidden .again.h5.lock and .again.h5.partial: the next run takes them over
    and says so (it used to take them over silently), and leaves neither behind."""
    folder = _copy(pendulum_run, tmp_path / "run")
    (folder / ".again.h5.lock").write_text("99999999\n")  # no process holds it
    (folder / ".again.h5.partial").write_bytes(b"half a file")
    result = runner.invoke(app, ["optimize", str(folder / "pendulum.yaml"), "-o", str(folder / "again.h5")])
    assert result.exit_code == 0, result.output
    warnings = [line for line in result.output.splitlines() if line.startswith("warning:")]
    assert warnings == [
        f"warning: took over {folder}/.again.h5.lock, left by process 99999999, which was killed",
        f"warning: removed {folder}/.again.h5.partial, left by an interrupted run",
    ], result.output
    assert not [p.name for p in folder.iterdir() if p.name.startswith(".again")]


def test_a_prior_regressor_of_three_dimensions_is_named_by_its_shape(pendulum_run, tmp_path):
    """A (2, 3, b) prior said 'has b regressor columns, the robot has b base parameters'."""
    folder = _copy(pendulum_run, tmp_path / "run")
    with h5py.File(folder / "prior3.h5", "w") as f:
        f["regressor"] = np.ones((2, 3, 3))
    config = {**yaml.safe_load((folder / "pendulum.yaml").read_text()), "output": "new.h5"}
    (folder / "prior3.yaml").write_text(yaml.safe_dump({**config, "sequence": {"iterations": 1, "prior": "prior3.h5"}}))
    assert_refused(folder, ["optimize", str(folder / "prior3.yaml")], "has regressor rows of shape 2x3x3")


# --- what excite did not write is never replaced (issue 85) ------------------------------------------


def _recording(folder: Path) -> Path:
    """A bag as ``ros2 bag record /joint_states`` writes one (no mark of excite's): 3 messages."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    with Writer(folder, version=8) as writer:
        connection = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=store)
        for k in range(3):
            stamp = types["builtin_interfaces/msg/Time"](sec=k, nanosec=0)
            message = types["sensor_msgs/msg/JointState"](
                header=types["std_msgs/msg/Header"](stamp=stamp, frame_id=""),
                name=["hinge"],
                position=np.zeros(1),
                velocity=np.zeros(0),
                effort=np.ones(1),
            )
            writer.write(connection, k * 10**9, store.serialize_cdr(message, "sensor_msgs/msg/JointState"))
    return folder


@pytest.mark.parametrize("force", [[], ["--force"]])
def test_a_lab_s_recording_at_an_output_is_never_replaced(pendulum_run, tmp_path, force):
    """Every writer with a recording excite did not write in the way: export's bag and file, simulate's
    bags and CSV runs, identify's report behind a dangling symbolic link; refused with and without
    --force, the recording untouched."""
    folder = _copy(pendulum_run, tmp_path / "run")
    _recording(folder / "fit")
    (folder / "bags").mkdir()
    _recording(folder / "bags" / "run_1")
    (folder / "csv").mkdir()
    (folder / "csv" / "run_1.csv").write_text("time,q_hinge,tau_hinge\n0,0,0\n")
    (folder / "play.csv").write_text("time,q_hinge,tau_hinge\n0,0,0\n")
    simulate = ["simulate", "out.h5", "effects.yaml"]
    bags = yaml.safe_load((folder / "effects.yaml").read_text()) | {"recording": "rosbag2"}
    (folder / "bag_effects.yaml").write_text(yaml.safe_dump(bags))
    cases = [
        (["export", "out.h5", "--format", "rosbag2", "-o", "fit"], "fit"),
        (["export", "out.h5", "-o", "play.csv"], "play.csv"),
        (["simulate", "out.h5", "bag_effects.yaml", "-o", "bags"], "run_1"),
        ([*simulate, "-o", "csv"], "run_1.csv"),
    ]
    for argv, named in cases:
        with chdir(folder):
            assert_refused(folder, argv + force, named)
    if not force:  # a dangling link: refused, not replaced by a file (with --force it is written through)
        (folder / "rep.h5").symlink_to(folder / "elsewhere" / "rep.h5")
        with chdir(folder):
            result = runner.invoke(app, ["identify", "id.yaml", "-o", "rep.h5"])
        assert result.exit_code == 2 and "rep.h5 exists" in result.output
        assert (folder / "rep.h5").is_symlink() and not (folder / "elsewhere").exists()


def test_a_symbolic_link_loop_at_an_output_is_one_line(tmp_path):
    (tmp_path / "a.yaml").symlink_to(tmp_path / "b.yaml")
    (tmp_path / "b.yaml").symlink_to(tmp_path / "a.yaml")
    assert_refused(tmp_path, ["init", "ur_description/urdf/ur3_robot.urdf", "-o", str(tmp_path / "a.yaml")], "loop")
