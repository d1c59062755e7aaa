"""The noise table identify prints: one row per joint with a, ρ and the kind the data prefer, read
from the report's fitted levels; a dead channel named; nothing without a fit."""

from dataclasses import replace

from rich.console import Console

from excite_cli.console.noise_levels import noise_table
from excite_cli.identification.fitting.noise_level import NoiseLevel


def _text(tables) -> str:
    console = Console(width=200, record=True)
    for table in tables:
        console.print(table)
    return console.export_text()


def test_each_joints_noise_and_the_kind_the_data_prefer_are_printed(simulated_identification):
    report = simulated_identification[1]
    levels = [NoiseLevel(0.05, 0.004, 0.0, 0.0, 0.06), NoiseLevel(0.01, 0.001, 0.02, 0.001, 0.012)] + [None] * 5
    text = _text(noise_table(replace(report, noise_levels=levels)))
    lines = {line.split("│")[1].strip(): line for line in text.splitlines() if line.count("│") > 2}
    assert "0.05 ± 0.004" in lines["panda_joint1"] and lines["panda_joint1"].rstrip("│ ").endswith("absolute")
    assert "0.06" in lines["panda_joint1"].split("│")[3] and "0.012" in lines["panda_joint2"].split("│")[3]
    assert "2 ± 0.1" in lines["panda_joint2"] and "growing with the torque" in lines["panda_joint2"]
    assert "no signal" in lines["panda_joint3"]
    assert _text(noise_table(replace(report, noise_levels=[]))) == ""


def test_the_shipped_simulated_runs_absolute_noise_is_preferred_on_every_joint(simulated_identification):
    report = simulated_identification[1]  # 0.05 Nm of white torque noise, nothing growing with the torque
    assert [level.preferred for level in report.noise_levels] == ["absolute"] * 7
    assert all(0.04 < level.absolute < 0.2 for level in report.noise_levels)  # noise and model error
