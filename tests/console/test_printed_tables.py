"""Printed tables keep every number when the output is a file or a pipe (a CI log), not a terminal."""

import re
import subprocess
import sys

from conftest import UR5, write_config

EXCITE = [sys.executable, "-m", "excite_cli"]


def _run_to_file(tmp_path, args, name):
    log = tmp_path / name
    with open(log, "w") as out:
        result = subprocess.run(
            EXCITE + args,
            stdout=out,
            stderr=subprocess.PIPE,
            text=True,
            cwd=tmp_path,
            env={"PATH": "/usr/bin:/bin", "COLUMNS": "60"},
            timeout=600,
        )
    return result, log.read_text()


def test_verify_gradient_table_in_a_file_keeps_its_numbers(tmp_path):
    config = write_config(tmp_path, UR5)
    result, text = _run_to_file(tmp_path, ["verify-gradient", str(config), "--objective", "log_cond"], "verify.log")
    assert result.returncode == 0, result.stderr
    assert "…" not in text
    rows = [line for line in text.splitlines() if "log_cond" in line]
    assert rows and all(len(re.findall(r"\d\.\d+e[-+]\d+", row)) >= 2 for row in rows)


def test_optimize_tables_in_a_file_keep_their_headers_and_numbers(tmp_path):
    config = write_config(
        tmp_path,
        {
            **UR5,
            "optimizer": {"restarts": 1, "max_iterations": 5, "workers": 1},
            "sequence": {"iterations": 1},
            "output": str(tmp_path / "r.h5"),
        },
    )
    result, text = _run_to_file(tmp_path, ["optimize", str(config)], "optimize.log")
    assert result.returncode == 0, result.stderr
    assert "…" not in text
    assert re.search(r"cond\(C(\(i\)|⁽ⁱ⁾)\)", text) and "KKT residual" in text and "end point" in text
    assert re.search(r"│\s+1\s+│\s+\d+\.\d+\s+│", text)  # Table I's first row, its numbers whole
