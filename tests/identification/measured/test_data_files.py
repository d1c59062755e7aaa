"""Measured data as labs have it: headerless CSV with currents and torque constants, NPZ, MAT, other
delimiters, and corrupt rows stopped on (naming file and line) or dropped and counted."""

from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io

from excite_cli.errors import ExciteError
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.data_config import RunConfig
from excite_cli.identification.measured.files import read_table
from excite_cli.identification.measured.measurements import Run, in_sample_validation, load_run, silent_channels

JOINTS = [f"panda_joint{k}" for k in range(1, 8)]
T = 400
TIME = np.arange(T) * 0.002
Q = np.sin(np.outer(TIME, np.arange(1, 8)))
TAU = 3.0 * np.cos(np.outer(TIME, np.arange(1, 8)))
KT = np.array([2.0, 2.5, 1.5, 3.0, 0.5, 0.8, 1.2])


def _load(tmp_path: Path, name: str, columns: dict, **data):
    problem = IdentifyProblem.model_validate(
        {
            "robot": {
                "urdf": "panda_description/urdf/panda.urdf",
                "source": "example-robot-data",
                "active_joints": JOINTS,
            },
            "data": {"runs": [{"file": name}], "columns": columns, **data},
        }
    )
    problem.source_path = tmp_path / "identify.yaml"
    return load_run(problem.data.runs[0], problem.data, problem.robot.active_joints, problem.folder)


def _check(run, dropped=0):
    rows = np.ones(T, bool)
    if dropped:
        rows[[5, 9][:dropped]] = False
    np.testing.assert_allclose(run.time, TIME[rows], rtol=1e-12)
    np.testing.assert_allclose(run.q, Q[rows], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(run.tau, TAU[rows], rtol=1e-12, atol=1e-14)
    assert run.dropped == dropped


@pytest.mark.parametrize("signs", [[1] * 7, [1, 1, -1, -1, -1, -1, -1]], ids=["positive", "vendor-negative"])
def test_headerless_csv_with_currents_and_torque_constants(tmp_path, signs):
    """τ = gain × current; a vendor's negative gains (a mobile manipulator's arm motors 3–7: reduction ×
    motor constant, e.g. 100 × −0.087 Nm/A) flip τ alone, q as recorded (data.signs would flip it too)."""
    gains = KT * np.array(signs)
    np.savetxt(tmp_path / "run.csv", np.column_stack([TIME, TAU / gains, Q]), delimiter=",", fmt="%.17g")
    run = _load(
        tmp_path,
        "run.csv",
        {"time": 0, "q": list(range(8, 15)), "current": list(range(1, 8))},
        torque_constants=gains.tolist(),
    )
    _check(run)


def test_npz_and_mat_runs(tmp_path):
    np.savez(tmp_path / "run.npz", t=TIME, q=Q, tau=TAU)
    _check(
        _load(
            tmp_path,
            "run.npz",
            {"time": "t", "q": [f"q[{k}]" for k in range(7)], "tau": [f"tau[{k}]" for k in range(7)]},
        )
    )
    scipy.io.savemat(tmp_path / "run.mat", {"t": TIME, "Q": Q.T, "tau": TAU})  # Q stored joints × samples
    _check(
        _load(
            tmp_path,
            "run.mat",
            {"time": "t", "q": [f"Q[{k}]" for k in range(7)], "tau": [f"tau[{k}]" for k in range(7)]},
        )
    )


def test_a_table_gives_its_columns_by_name_or_position(tmp_path):
    np.savetxt(
        tmp_path / "run.csv",
        np.column_stack([TIME, Q]),
        delimiter=",",
        fmt="%.17g",
        header=",".join(["t"] + [f"q{k}" for k in range(1, 8)]),
        comments="",
    )
    table = read_table(tmp_path / "run.csv")
    np.testing.assert_array_equal(table.column("q3", "q", tmp_path / "run.csv"), Q[:, 2])
    np.testing.assert_array_equal(table.column(0, "time", tmp_path / "run.csv"), TIME)
    with pytest.raises(ExciteError, match="q9"):
        table.column("q9", "q", tmp_path / "run.csv")


def test_semicolon_csv_with_header(tmp_path):
    header = ";".join(["time"] + [f"q{k}" for k in range(7)] + [f"t{k}" for k in range(7)])
    np.savetxt(
        tmp_path / "run.csv", np.column_stack([TIME, Q, TAU]), delimiter=";", header=header, comments="", fmt="%.17g"
    )
    _check(_load(tmp_path, "run.csv", {"q": [f"q{k}" for k in range(7)], "tau": [f"t{k}" for k in range(7)]}))


def test_semicolon_csv_with_decimal_commas(tmp_path):
    header = ";".join(["time"] + [f"q{k}" for k in range(7)] + [f"t{k}" for k in range(7)])
    rows = [";".join(f"{v:.17g}".replace(".", ",") for v in row) for row in np.column_stack([TIME, Q, TAU])]
    (tmp_path / "run.csv").write_text("\n".join([header] + rows) + "\n")
    _check(_load(tmp_path, "run.csv", {"q": [f"q{k}" for k in range(7)], "tau": [f"t{k}" for k in range(7)]}))


def _corrupt_csv(tmp_path: Path) -> dict:
    lines = [",".join(["time"] + [f"q{k}" for k in range(7)] + [f"t{k}" for k in range(7)])]
    lines += [",".join(f"{v:.17g}" for v in row) for row in np.column_stack([TIME, Q, TAU])]
    lines[6] = lines[6].replace(lines[6].split(",")[3], "1e306", 1)  # data row 6: a corrupt value
    lines[10] = ",".join(lines[10].split(",")[:5])  # data row 10: too few columns
    (tmp_path / "run.csv").write_text("\n".join(lines) + "\n")
    return {"q": [f"q{k}" for k in range(7)], "tau": [f"t{k}" for k in range(7)]}


def test_corrupt_rows_stop_with_file_and_line_or_are_dropped_and_counted(tmp_path):
    columns = _corrupt_csv(tmp_path)
    with pytest.raises(ExciteError, match=r"run.csv: line 11: 5 values where the header has 15"):
        _load(tmp_path, "run.csv", columns)
    lines = (tmp_path / "run.csv").read_text().splitlines()
    del lines[10]
    (tmp_path / "run.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(ExciteError, match=r"run.csv: a value beyond ±1e\+06 in q at data row 6"):
        _load(tmp_path, "run.csv", columns)
    _corrupt_csv(tmp_path)
    _check(_load(tmp_path, "run.csv", columns, bad_rows="drop"), dropped=2)


@pytest.mark.parametrize(
    "name, content, message",
    [
        ("run.csv", bytes(range(256)) * 4, "is not a text file"),
        ("run.npz", b"not a zip archive", "cannot read run.npz as NPZ"),
        ("run.h5", b"not HDF5 at all", "cannot read run.h5 as H5"),
        ("run.csv", b"", "has no data rows"),
    ],
)
def test_unreadable_files_give_one_message(tmp_path, name, content, message):
    (tmp_path / name).write_bytes(content)
    with pytest.raises(ExciteError, match=message):
        _load(tmp_path, name, {"q": ["q0"] * 7, "tau": ["t0"] * 7})


def test_an_excite_result_given_as_data_names_the_missing_column(tmp_path):
    with h5py.File(tmp_path / "result.h5", "w") as f:
        f["table"] = np.zeros(3, dtype=[("iteration", "i4"), ("cond_own", "f8")])
        f["iterations/1/alpha"] = np.zeros((7, 3))
    with pytest.raises(ExciteError, match="data"):
        _load(tmp_path, "result.h5", {"q": ["q0"] * 7, "tau": ["t0"] * 7})


def test_a_validation_run_that_is_a_fit_run_over_the_same_times_is_warned_about(tmp_path):
    def runs(*specs):
        return [RunConfig(file=f, role=role, crop=crop) for f, role, crop in specs]

    same = in_sample_validation(runs(("a.csv", "fit", None), ("./a.csv", "validation", None)), tmp_path)
    assert len(same) == 1 and "in-sample" in same[0]
    apart = runs(("a.csv", "fit", (0.0, 10.0)), ("a.csv", "validation", (10.5, 20.0)), ("b.csv", "validation", None))
    assert in_sample_validation(apart, tmp_path) == []  # crops apart, or another recording
    overlap = runs(("a.csv", "fit", (0.0, 10.0)), ("a.csv", "validation", (5.0, 20.0)))
    assert len(in_sample_validation(overlap, tmp_path)) == 1
    touching = runs(("a.csv", "fit", (0.1, 5.3)), ("a.csv", "validation", (5.3, 7.5)))
    assert in_sample_validation(touching, tmp_path) == []  # one shared instant is no shared motion


def _run(name: str, tau: np.ndarray) -> Run:
    return Run(name, "fit", TIME, Q, None, None, tau)


def test_a_channel_silent_in_one_recording_the_others_record_is_refused_naming_both():
    """Issue 102: one recording's joint-4 torque all zeros while the others record it was fitted as the
    joint's torque (rms after 1-7 Nm): refused naming the file and the joint."""
    dead = TAU.copy()
    dead[:, 3] = 0.0
    with pytest.raises(ExciteError) as refused:
        silent_channels([_run("a.csv", TAU), _run("b.csv", dead), _run("c.csv", TAU)], JOINTS)
    assert refused.value.field == "data.runs"
    assert "b.csv" in str(refused.value) and "panda_joint4" in str(refused.value)
    assert "panda_joint3" not in str(refused.value)
    # silent in every recording: a channel not recorded at all, named as dead by the fit
    silent = silent_channels([_run("a.csv", dead), _run("b.csv", dead)], JOINTS)
    assert list(np.flatnonzero(silent)) == [3]
    assert not np.any(silent_channels([_run("a.csv", TAU), _run("b.csv", TAU)], JOINTS))
