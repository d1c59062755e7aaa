"""The one opener every input file goes through: a regular file passes, anything else is one error
naming the field, before anything opens it (a FIFO nobody writes would block a reader for ever)."""

import os
import socket

import pytest

from excite_cli.errors import ExciteError, FileNotFound
from excite_cli.inputs import input_file


def test_a_regular_file_and_a_link_to_one_pass(tmp_path):
    (tmp_path / "a.yaml").write_text("x: 1")
    (tmp_path / "link.yaml").symlink_to(tmp_path / "a.yaml")
    assert input_file(tmp_path / "a.yaml", "config") == tmp_path / "a.yaml"
    assert input_file(str(tmp_path / "link.yaml"), "config") == tmp_path / "link.yaml"


def test_missing_files_and_dangling_links_are_not_found(tmp_path):
    (tmp_path / "dangling.h5").symlink_to(tmp_path / "gone.h5")
    for name in ("none.h5", "dangling.h5"):
        with pytest.raises(FileNotFound, match=f"HDF5 file not found: .*{name}") as caught:
            input_file(tmp_path / name, "result", "HDF5 file")
        assert caught.value.field == "result"


@pytest.mark.parametrize("kind", ["folder", "fifo", "socket", "device"])
def test_what_is_not_a_regular_file_is_named(tmp_path, kind):
    path = tmp_path / "odd"
    if kind == "folder":
        path.mkdir()
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "socket":
        server = socket.socket(socket.AF_UNIX)
        server.bind(str(path))
    else:
        path = "/dev/null"
    expected = {"folder": "is a folder", "fifo": "is a FIFO", "socket": "is a socket", "device": "is a device"}[kind]
    with pytest.raises(ExciteError, match=expected) as caught:
        input_file(path, "data.runs", "data file")
    assert caught.value.field == "data.runs" and caught.value.expected == "a data file"


def test_the_article_fits_the_word():
    with pytest.raises(ExciteError) as caught:
        input_file("/dev/null", "report", "HDF5 file")
    assert caught.value.expected == "an HDF5 file"
    with pytest.raises(ExciteError) as caught:
        input_file("/dev/null", "robot.urdf", "URDF")
    assert caught.value.expected == "a URDF"
