"""Every option's help reaches the user whole: rich, which draws `--help`, reads "[…]" as markup and
drops it (a unit in brackets vanished from `verify-gradient --help`)."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.console.app import EXAMPLES
from excite_cli.dynamics.robot_files import installed_share

MARKUP = re.compile(r"(?<!\\)\[[^\]]*\]")


def test_no_option_help_holds_what_rich_takes_for_markup():
    group = typer.main.get_command(app)
    swallowed = [
        f"{name} {param.name}: {param.help}"
        for name, command in group.commands.items()
        for param in command.params
        if MARKUP.search(getattr(param, "help", None) or "")
    ]
    assert not swallowed


def test_the_step_unit_is_shown():
    result = CliRunner().invoke(app, ["verify-gradient", "--help"], terminal_width=200)
    assert "Finite-difference step (rad)." in result.output


ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_each_help_example_runs_as_written(name, tmp_path, monkeypatch):
    """The ``Example:`` line of ``excite NAME --help``, run from a folder laid out as the repository's."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "configs").symlink_to(ROOT / "configs")
    shown = CliRunner().invoke(app, [name, "--help"], terminal_width=200).output
    [line] = re.findall(r"Example: (excite .*?)\s*$", shown, flags=re.M)
    assert line == EXAMPLES[name]
    result = CliRunner().invoke(app, shlex.split(line)[1:], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output


def test_every_example_robot_data_path_in_a_help_exists():
    group = typer.main.get_command(app)
    texts = [param.help or "" for command in group.commands.values() for param in command.params]
    paths = {p for text in texts for p in re.findall(r"[\w-]+_description/[\w/.-]+\.urdf", text)}
    share = installed_share() / "example-robot-data" / "robots"
    assert paths and all((share / p).is_file() for p in paths), paths
