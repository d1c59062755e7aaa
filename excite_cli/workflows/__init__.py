"""One library function per study a command runs; they check their output paths before computing."""

from excite_cli.workflows.check import plan_optimize
from excite_cli.workflows.compare import run_compare_random
from excite_cli.workflows.export import run_export
from excite_cli.workflows.identify import run_identify
from excite_cli.workflows.init import run_init
from excite_cli.workflows.optimize import run_optimize
from excite_cli.workflows.schema import run_schema
from excite_cli.workflows.simulate import simulate_runs
from excite_cli.workflows.validate import run_validate
from excite_cli.workflows.verify_gradient import run_verify
from excite_cli.workflows.view import run_view

__all__ = [
    "plan_optimize",
    "run_compare_random",
    "run_export",
    "run_identify",
    "run_init",
    "run_optimize",
    "run_schema",
    "run_validate",
    "run_verify",
    "run_view",
    "simulate_runs",
]
