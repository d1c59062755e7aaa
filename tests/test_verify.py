"""`excite verify-gradient` reports a small error and a speed-up, from the command line."""

import re

from typer.testing import CliRunner

from conftest import UR5, write_config
from excite_cli.cli import app


def test_verify_gradient_command(tmp_path):
    result = CliRunner().invoke(app, ["verify-gradient", str(write_config(tmp_path, UR5))], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    row = next(line for line in result.output.splitlines() if "random" in line)
    numbers = re.findall(r"\d\.\d+e[-+]\d+", row)
    assert float(numbers[0]) < 1e-6  # central-difference relative error
