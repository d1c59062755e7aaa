"""What the command line prints: tables and progress bars (rich).

The table modules are imported on first use (PEP 562): they import the studies whose results they
print, which ``excite --help`` and ``--version`` need not load."""

from importlib import import_module

_LAZY = ("bodies", "export_lines", "identification", "model_files", "plans", "rehearsal", "tables")


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return import_module(f"{__name__}.{name}")
