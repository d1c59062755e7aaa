"""Output paths checked before any work, and one run at a time on an output."""

import os

import pytest

from excite_cli.errors import ExciteError, OutputExists
from excite_cli.storage.paths import check_folder, check_target, output_lock


def test_an_existing_output_is_kept_without_force_and_a_folder_never_replaced(tmp_path):
    (tmp_path / "r.h5").write_text("kept")
    with pytest.raises(OutputExists):
        check_target(tmp_path / "r.h5", "output")
    assert check_target(tmp_path / "r.h5", "output", force=True) == tmp_path / "r.h5"
    (tmp_path / "folder.h5").mkdir()
    with pytest.raises(ExciteError, match="folder"):
        check_target(tmp_path / "folder.h5", "output", force=True)
    os.mkfifo(tmp_path / "pipe.h5")
    with pytest.raises(ExciteError):
        check_target(tmp_path / "pipe.h5", "output", force=True)
    assert (tmp_path / "r.h5").read_text() == "kept"


def test_a_folder_that_cannot_be_made_is_refused(tmp_path):
    (tmp_path / "file").write_text("")
    with pytest.raises(ExciteError, match="is a file"):
        check_target(tmp_path / "file" / "r.h5", "output")


def test_a_folder_of_runs_is_checked_for_every_file(tmp_path):
    (tmp_path / "run_2.csv").write_text("")
    with pytest.raises(OutputExists):
        check_folder(tmp_path, ["run_1.csv", "run_2.csv"], "output_dir")
    assert check_folder(tmp_path, ["run_1.csv", "run_2.csv"], "output_dir", force=True) == tmp_path


def test_a_second_run_on_one_output_stops_at_once(tmp_path):
    with output_lock(tmp_path / "r.h5", "output"):
        with pytest.raises(ExciteError, match="r.h5"):
            with output_lock(tmp_path / "r.h5", "output"):
                pass
    with output_lock(tmp_path / "r.h5", "output"):  # released: taken again
        pass
    assert not (tmp_path / ".r.h5.lock").exists()
