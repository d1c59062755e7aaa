"""Errors carry the field at fault, the offending value and what is expected; the library names
arguments and config fields, the command line words them as its own options."""

import os
from pathlib import Path

import pytest
import yaml
from conftest import UR5, write_config

from excite_cli.atomic import atomic_folder, atomic_folders, atomic_path
from excite_cli.config_file import load_problem
from excite_cli.errors import CannotWrite, ExciteError, ExciteWarning, FileNotFound, OutputExists
from excite_cli.h5 import open_h5
from excite_cli.storage.paths import check_target
from excite_cli.workflows.export import played_result


def test_a_config_value_out_of_range_names_its_field_value_and_file(tmp_path):
    path = write_config(tmp_path, {**UR5, "trajectory": {**UR5["trajectory"], "harmonics": -2}})
    with pytest.raises(ExciteError) as caught:
        load_problem(path)
    error = caught.value
    assert (error.field, error.value, error.source) == ("trajectory.harmonics", -2, path)
    assert str(error).startswith(f"{path}: trajectory.harmonics: ")


def test_library_errors_name_arguments_not_flags(tmp_path):
    with pytest.raises(FileNotFound) as missing:
        played_result(tmp_path / "none.h5")
    assert (missing.value.field, missing.value.value) == ("result", tmp_path / "none.h5")
    with pytest.raises(ExciteError) as rate:
        played_result(tmp_path / "none.h5", rate=-1.0)
    assert (rate.value.field, rate.value.value) == ("rate", -1.0) and "100000" in rate.value.expected
    (tmp_path / "there.h5").write_bytes(b"")
    with pytest.raises(OutputExists) as exists:
        check_target(tmp_path / "there.h5", "output")
    assert exists.value.field == "output" and "--" not in str(exists.value)


def test_an_atomic_write_that_fails_leaves_nothing_and_names_its_field(tmp_path):
    target = tmp_path / "out.csv"
    with pytest.raises(CannotWrite) as caught:
        with atomic_path(target, "output_dir") as tmp:
            tmp.write_text("half")
            raise OSError(28, "No space left on device")
    assert caught.value.field == "output_dir" and "No space left" in caught.value.reason
    assert list(tmp_path.iterdir()) == []
    with atomic_path(target) as tmp:
        tmp.write_text("whole")
    assert target.read_text() == "whole" and list(tmp_path.iterdir()) == [target]


def test_an_atomic_folder_is_whole_or_absent_and_replaces_the_one_there(tmp_path):
    target = tmp_path / "new" / "bag"
    with pytest.raises(CannotWrite) as caught:
        with atomic_folder(target) as staging:
            staging.mkdir()
            (staging / "half.db3").write_text("half")
            raise OSError(28, "No space left on device")
    assert "No space left" in caught.value.reason and list(tmp_path.iterdir()) == []  # nor the folder made for it
    for text in ("first", "second"):
        with atomic_folder(target) as staging:
            staging.mkdir()
            (staging / "bag.db3").write_text(text)
    assert [p.name for p in target.iterdir()] == ["bag.db3"] and (target / "bag.db3").read_text() == "second"
    assert [p.name for p in target.parent.iterdir()] == ["bag"]
    (target.parent / ".bag.partial").mkdir()  # left by a killed run
    with pytest.warns(ExciteWarning, match="left by an interrupted run"):
        with atomic_folder(target) as staging:
            staging.mkdir()
    assert [p.name for p in target.parent.iterdir()] == ["bag"]


def test_an_atomic_folder_that_cannot_take_its_place_puts_back_the_one_it_replaced(tmp_path, monkeypatch):
    """The replaced folder is set aside, not removed, until the new one is in place (issue 62: --force
    never removes what it replaces before the new one is complete)."""
    target = tmp_path / "bag"
    target.mkdir()
    (target / "bag.db3").write_text("earlier")
    moves, replace = [], os.replace

    def failing(source, destination):
        moves.append(Path(destination).name)
        if len(moves) == 2:  # the new folder onto the target
            raise OSError(18, "Invalid cross-device link")
        replace(source, destination)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(CannotWrite, match="cross-device"):
        with atomic_folder(target) as staging:
            staging.mkdir()
            (staging / "bag.db3").write_text("new")
    monkeypatch.setattr(os, "replace", replace)
    assert (target / "bag.db3").read_text() == "earlier" and [p.name for p in tmp_path.iterdir()] == ["bag"]


def test_a_set_of_atomic_folders_that_cannot_all_take_their_place_puts_every_earlier_one_back(tmp_path, monkeypatch):
    """The second of two folders cannot be moved in: the first new one goes out again and both earlier
    ones return."""
    targets = [tmp_path / "run_1", tmp_path / "run_2"]
    for target in targets:
        target.mkdir()
        (target / "bag.db3").write_text(f"earlier {target.name}")
    moves, replace = [], os.replace

    def failing(source, destination):
        moves.append(Path(destination).name)
        if moves == [".replaced", "run_1", ".replaced", "run_2"]:  # the second new folder onto its target
            raise OSError(18, "Invalid cross-device link")
        replace(source, destination)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(CannotWrite, match="cross-device"):
        with atomic_folders(targets) as stagings:
            for staging in stagings:
                staging.mkdir()
                (staging / "bag.db3").write_text("new")
    monkeypatch.setattr(os, "replace", replace)
    assert [(t / "bag.db3").read_text() for t in targets] == ["earlier run_1", "earlier run_2"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run_1", "run_2"]


def test_a_file_that_is_not_hdf5_is_named_with_the_field_that_gave_it(tmp_path):
    path = tmp_path / "prior.h5"
    path.write_text(yaml.safe_dump({"not": "hdf5"}))
    with pytest.raises(ExciteError) as caught:
        with open_h5(path, "sequence.prior"):
            pass
    assert caught.value.field == "sequence.prior" and caught.value.value == path
