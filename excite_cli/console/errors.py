"""Errors worded for the command line, one style for every command: ``error: WHERE: problem``, where
WHERE is an argument as the command spells it (``CONFIG``, ``REPORT``, ``--output``), a config field
after the file it is in (``problem.yaml: limits.velocity``), or the option that overrode a config
field (``--iterations`` for ``sequence.iterations``); an existing output says how to replace it."""

from __future__ import annotations

import inspect
import re
import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterator, Optional

from rich.console import Console
from rich.markup import escape
from typer.models import ArgumentInfo, OptionInfo

from excite_cli.errors import ExciteError, ExciteWarning, OutputExists

#: A config field an option's help says the option overrides: "(optimizer.seed)", "(optimizer.workers; ...".
OVERRIDDEN = re.compile(r"\(([a-z_]+(?:\.[a-z_]+)+)[;)]")


def spellings(command: Callable, given: Optional[dict] = None) -> dict[str, str]:
    """How ``command`` (a typer command function) spells its parameters: an option by its long flag
    (``--output``), an argument by its name in capitals (``REPORT``); keyed by the parameter's name,
    by the flag's name (``fmt`` and ``format`` → ``--format``) and by the config field an option
    overrides, as its help names it (``--iterations`` for "... (sequence.iterations)"), when the call's
    arguments ``given`` hold that option (a field the config file set is named as in the file)."""
    spelled = {}
    for name, parameter in inspect.signature(command).parameters.items():
        default = parameter.default
        if isinstance(default, OptionInfo):
            flags = [d for d in default.param_decls if d.startswith("--")] or [f"--{name.replace('_', '-')}"]
            spelled[name] = spelled[flags[0][2:].replace("-", "_")] = flags[0]
            if given is None or given.get(name) is not None:
                for dotted in OVERRIDDEN.findall(default.help or ""):
                    spelled[dotted] = flags[0]
        elif isinstance(default, ArgumentInfo):
            spelled[name] = name.upper()
    return spelled


def word(error: ExciteError, spelled: dict[str, str], config: Optional[Path] = None) -> str:
    """One line for ``error``: its field as the command spells it; a config field after ``config``,
    the command's config file, when the error does not name the file it is in."""
    field = None if error.source else spelled.get(error.field)  # a field in a file is written as in the file
    line = error.describe(field, config if field is None else None)
    if isinstance(error, OutputExists):
        line += f"; use {spelled.get('force', '--force')} to replace it"
    return line


@contextmanager
def printed_warnings(console: Console) -> Iterator[None]:
    """Every :class:`~excite_cli.errors.ExciteWarning` raised in the block printed on ``console`` as
    one line ``warning: ...``, once per message (a base computed by two steps of a command warns
    once); other warnings as Python shows them, but numpy's floating-point ones (an overflow, a
    division by zero), which the block does not show: what such a number reaches is refused by the
    range checks with its field, not as numpy's line."""
    import numpy as np  # here, not at start-up: a command's, which computes with it anyway

    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("always", ExciteWarning)
        python_way = warnings.showwarning
        said: set[str] = set()

        def show(message, category, *args, **kwargs) -> None:
            if issubclass(category, ExciteWarning):
                if str(message) in said:
                    return
                said.add(str(message))
                console.print(f"[bold yellow]warning:[/] {escape(str(message))}", highlight=False, soft_wrap=True)
            else:
                python_way(message, category, *args, **kwargs)

        warnings.showwarning = show
        yield
