"""One library function per study a command runs; they check their output paths before computing.

Imported on first use (PEP 562): ``excite --help`` and ``--version`` load none of them, and a command
loads only its own study's modules (scipy, matplotlib, cvxpy where it needs them)."""

from importlib import import_module

#: Each function and the module of this package that defines it.
_MODULES = {
    "plan_check": "check_identify",
    "plan_optimize": "check",
    "run_compare_random": "compare",
    "run_export": "export",
    "run_identify": "identify",
    "run_init": "init",
    "run_optimize": "optimize",
    "run_rehearse": "rehearse",
    "run_schema": "schema",
    "run_validate": "validate",
    "run_verify": "verify_gradient",
    "run_view": "view",
    "simulate_runs": "simulate",
}

__all__ = sorted(_MODULES)


def __getattr__(name: str):
    if name not in _MODULES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f"{__name__}.{_MODULES[name]}"), name)
