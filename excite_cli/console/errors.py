"""Errors worded for the command line: a library error names the argument or config field at fault
(``output``, ``limits.velocity``); here an argument becomes the command's own spelling of it
(``--output``, ``REPORT``), and an existing output says how to replace it."""

from __future__ import annotations

import inspect
from typing import Callable

from typer.models import ArgumentInfo, OptionInfo

from excite_cli.errors import ExciteError, OutputExists


def spellings(command: Callable) -> dict[str, str]:
    """How ``command`` (a typer command function) spells its parameters: an option by its long flag
    (``--output``), an argument by its name in capitals (``REPORT``); keyed by the parameter's name
    and by the flag's name (``fmt`` and ``format`` → ``--format``)."""
    spelled = {}
    for name, parameter in inspect.signature(command).parameters.items():
        default = parameter.default
        if isinstance(default, OptionInfo):
            flags = [d for d in default.param_decls if d.startswith("--")] or [f"--{name.replace('_', '-')}"]
            spelled[name] = spelled[flags[0][2:].replace("-", "_")] = flags[0]
        elif isinstance(default, ArgumentInfo):
            spelled[name] = name.upper()
    return spelled


def word(error: ExciteError, spelled: dict[str, str]) -> str:
    """One line for ``error``: its field as the command spells it (config fields as they are)."""
    line = error.describe(spelled.get(error.field))
    if isinstance(error, OutputExists):
        line += f"; use {spelled.get('force', '--force')} to replace it"
    return line
