"""Start-up: `excite --help` and `--version` load the command line's frame (typer, rich) and nothing a
command needs only once it runs: no numpy, scipy, pinocchio, pydantic, h5py, matplotlib, cvxpy or numba."""

import json
import subprocess
import sys

HEAVY = ("numpy", "scipy", "pinocchio", "pydantic", "h5py", "matplotlib", "cvxpy", "coal", "yaml", "numba")


def test_importing_the_command_line_loads_no_study_module():
    code = "import json, sys, excite_cli.cli; print(json.dumps(sorted(sys.modules)))"
    loaded = json.loads(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout)
    assert [m for m in loaded if m.split(".")[0] in HEAVY] == []
    assert "excite_cli.workflows.optimize" not in loaded and "excite_cli.config_file" not in loaded


def test_version_and_help_answer_from_the_light_frame():
    for argv in (["--version"], ["--help"]):
        result = subprocess.run([sys.executable, "-m", "excite_cli", *argv], capture_output=True, text=True)
        assert result.returncode == 0 and "excite" in result.stdout, result.stderr
