"""Output paths checked before any work, one run at a time on an output, and nothing replaced that
excite did not write: every writer's mark recognised, a user's file of each kind refused even with
force, a symbolic link written through and never replaced."""

import os

import h5py
import matplotlib.pyplot as plt
import numpy as np
import pytest

from excite_cli.atomic import MARK, atomic_path
from excite_cli.errors import ExciteError, OutputExists
from excite_cli.h5 import atomic_h5
from excite_cli.plots.figure import save_figure
from excite_cli.storage.paths import check_folder, check_target, output_lock, written_by_excite


def test_an_existing_output_is_kept_without_force_and_a_folder_never_replaced(tmp_path):
    (tmp_path / "r.h5").write_text(f"# {MARK} export")
    with pytest.raises(OutputExists):
        check_target(tmp_path / "r.h5", "output")
    assert check_target(tmp_path / "r.h5", "output", force=True) == tmp_path / "r.h5"
    (tmp_path / "r.h5").write_text("kept")
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
    (tmp_path / "run_2.csv").write_text(f"# {MARK} simulate\n")
    with pytest.raises(OutputExists):
        check_folder(tmp_path, ["run_1.csv", "run_2.csv"], "output_dir")
    assert check_folder(tmp_path, ["run_1.csv", "run_2.csv"], "output_dir", force=True) == tmp_path
    (tmp_path / "run_1.csv").write_text("time,q,tau\n")  # a recording of the lab's
    with pytest.raises(ExciteError, match="run_1.csv exists and excite did not write it"):
        check_folder(tmp_path, ["run_1.csv", "run_2.csv"], "output_dir", force=True)


def test_a_second_run_on_one_output_stops_at_once(tmp_path):
    with output_lock(tmp_path / "r.h5", "output"):
        with pytest.raises(ExciteError, match="r.h5"):
            with output_lock(tmp_path / "r.h5", "output"):
                pass
    with output_lock(tmp_path / "r.h5", "output"):  # released: taken again
        pass
    assert not (tmp_path / ".r.h5.lock").exists()


def test_every_kind_of_file_excite_writes_is_recognised_and_the_same_kind_from_elsewhere_is_not(tmp_path):
    """Excite's whole mark, not a mention of it: the lab files a loose mark took for excite's (a note
    saying NOT written by excite, a tool named excite_recorder, a lab note quoting the mark, a copied
    export header line, a person's name in an NPZ's written_by, a lab's own matplotlib figure)."""
    with atomic_h5(tmp_path / "ours.h5") as f:
        f["x"] = 1.0
    with h5py.File(tmp_path / "theirs.h5", "w") as f:
        f["x"] = 1.0
    with h5py.File(tmp_path / "theirs_recorder.h5", "w") as f:
        f.attrs["written_by"] = "written by excite_recorder 2.0"
    save_figure(plt.figure(), tmp_path / "ours.png", 20)
    plt.figure().savefig(tmp_path / "theirs.png", metadata={"Software": "a lab's script"})
    plt.figure().savefig(tmp_path / "theirs_matplotlib.png")
    np.savez(tmp_path / "ours.npz", q=np.zeros(2), written_by=np.array(f"{MARK} export"))
    np.savez(tmp_path / "theirs.npz", q=np.zeros(2))
    np.savez(tmp_path / "theirs_named.npz", q=np.zeros(2), written_by=np.array("Alice, panda-lab"))
    (tmp_path / "ours.csv").write_text(f"time_s\n0\n# excite export: iteration 1, 1000 Hz\n# {MARK} export\n")
    (tmp_path / "ours.xml").write_text(f"<!-- {MARK} identify -->\n<mujoco/>")
    (tmp_path / "theirs.csv").write_text("time,q,tau\n0,0,0\n")
    (tmp_path / "theirs_not.csv").write_text("# NOT written by excite: measured on panda-lab\ntime,q\n0,0\n")
    (tmp_path / "theirs_recorder.csv").write_text("# written by excite_recorder 1.2\ntime,q\n0,0\n")
    (tmp_path / "theirs_note.csv").write_text(f"time,q\n0,0\n# lab note: the plan was {MARK} export\n")
    (tmp_path / "theirs_copied.csv").write_text("# excite export: iteration 1, 1000 Hz\ntime,q\n0,0\n")
    (tmp_path / "theirs.yaml").write_text("# hand-tuned, NOT written by excite init\nrobot: {}\n")
    (tmp_path / "theirs.urdf").write_text('<robot name="arm"><!-- made with care, not by excite --></robot>')
    ours = sorted(p.name for p in tmp_path.iterdir() if written_by_excite(p))
    assert ours == ["ours.csv", "ours.h5", "ours.npz", "ours.png", "ours.xml"]
    for theirs in sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("theirs")):
        before = (tmp_path / theirs).read_bytes()
        with pytest.raises(ExciteError, match="excite did not write it"):
            check_target(tmp_path / theirs, "output", force=True)
        assert (tmp_path / theirs).read_bytes() == before


def test_a_symbolic_link_is_refused_without_force_and_written_through_with_it(tmp_path):
    (tmp_path / "kept.csv").write_text(f"# {MARK} export\n")
    (tmp_path / "link.csv").symlink_to(tmp_path / "kept.csv")
    (tmp_path / "dangling.h5").symlink_to(tmp_path / "nowhere" / "r.h5")
    for link in ("link.csv", "dangling.h5"):
        with pytest.raises(OutputExists):
            check_target(tmp_path / link, "output")
    assert check_target(tmp_path / "dangling.h5", "output", force=True) == tmp_path / "nowhere" / "r.h5"
    with atomic_path(tmp_path / "link.csv") as tmp:
        tmp.write_text("new")
    assert (tmp_path / "link.csv").is_symlink() and (tmp_path / "kept.csv").read_text() == "new"
    (tmp_path / "a.yaml").symlink_to(tmp_path / "b.yaml")
    (tmp_path / "b.yaml").symlink_to(tmp_path / "a.yaml")
    for force in (False, True):
        with pytest.raises(ExciteError, match="a loop of symbolic links"):
            check_target(tmp_path / "a.yaml", "output", force)
