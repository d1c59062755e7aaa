"""Every option's help reaches the user whole: rich, which draws `--help`, reads "[…]" as markup and
drops it (a unit in brackets vanished from `verify-gradient --help`)."""

from __future__ import annotations

import re

import typer
from typer.testing import CliRunner

from excite_cli.cli import app

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
