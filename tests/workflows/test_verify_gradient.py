"""`excite verify-gradient` reports a small error and a speed-up, from the command line."""

from conftest import UR5, write_config
from typer.testing import CliRunner

from excite_cli.cli import app


def test_verify_gradient_command(tmp_path):
    result = CliRunner().invoke(app, ["verify-gradient", str(write_config(tmp_path, UR5))], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    rows = [line for line in result.output.splitlines() if "random" in line and "×" in line]
    assert [name for name in ("log_cond", "log_det", "sigma_min") if any(name in row for row in rows)] == [
        "log_cond",
        "log_det",
        "sigma_min",
    ]
    for row in rows:
        cells = [cell.strip() for cell in row.split("│")]
        assert float(cells[5]) < 1e-6  # the central-difference relative error's column
    assert "PASS" in result.output


def test_verify_gradient_fails_with_status_1_above_the_tolerance(tmp_path):
    result = CliRunner().invoke(
        app,
        ["verify-gradient", str(write_config(tmp_path, UR5)), "--objective", "cond", "--tolerance", "1e-15"],
        env={"COLUMNS": "200"},
    )
    assert result.exit_code == 1 and "FAIL" in result.output
