"""The command line's frame: printed items are shown as written (brackets are not markup, lists are
flattened), and a command's bad input is one line and exit 2, an interruption its own status."""

import io
import subprocess
import sys
from pathlib import Path

import pytest
import typer
from conftest import pendulum_config
from rich.console import Console

from excite_cli.console import app as frame
from excite_cli.errors import ExciteError


def test_say_prints_text_as_written_and_flattens_lists():
    console = Console(file=io.StringIO(), width=200)
    frame.say("tau0[run.csv] in [Nm]", ["a [b]", "c"], console=console)
    assert console.file.getvalue().splitlines() == ["tau0[run.csv] in [Nm]", "a [b]", "c"]


@pytest.mark.parametrize(
    "raised, status, line",
    [
        (ExciteError("limits.velocity", "must be positive"), 2, "error: limits.velocity: must be positive"),
        (KeyboardInterrupt(), 130, "interrupted"),
    ],
)
def test_a_command_s_error_is_one_line_and_its_status(monkeypatch, raised, status, line):
    console = Console(file=io.StringIO(), width=200)
    monkeypatch.setattr(frame, "err", console)
    count = len(frame.app.registered_commands)

    def probe() -> None:
        raise raised

    try:
        guarded = frame.command("probe")(probe)
        with pytest.raises(typer.Exit) as exit:
            guarded()
    finally:
        del frame.app.registered_commands[count:]
    assert exit.value.exit_code == status and console.file.getvalue().strip() == line


def test_quiet_prints_nothing_but_errors(tmp_path):
    """``--quiet`` (scripts): no table, no progress; the result is written and an error is still its one line."""
    config = pendulum_config(tmp_path)
    excite = str(Path(sys.executable).with_name("excite"))
    run = subprocess.run([excite, "--quiet", "optimize", str(config)], capture_output=True, text=True, timeout=240)
    assert run.returncode == 0 and run.stdout == "", run.stdout
    assert "iteration" not in run.stderr and "cond" not in run.stderr, run.stderr
    assert (tmp_path / "out.h5").is_file()
    run = subprocess.run([excite, "-q", "optimize", str(config)], capture_output=True, text=True, timeout=240)
    errors = [line for line in run.stderr.splitlines() if line.startswith("error:")]
    assert run.returncode == 2 and len(errors) == 1 and "out.h5 exists" in errors[0], run.stderr
