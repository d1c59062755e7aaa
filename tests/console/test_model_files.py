"""What identify prints about the MJCF it wrote: the fields MuJoCo read back, the three validation
errors, MuJoCo's check and every effect the file could not hold, with its share of the error."""

import io

import mujoco
from rich.console import Console

from excite_cli.console.model_files import mjcf_written
from excite_cli.identification.effects import Term
from excite_cli.workflows.identify import IdentifyRun, write_identified_mjcf


def test_the_mjcf_lines_give_the_fields_the_errors_and_what_the_file_lacks(simulated_identification, tmp_path):
    problem, report, robot, base, _ = simulated_identification
    model, check = write_identified_mjcf(problem, report, robot, base, tmp_path / "panda.xml")
    model.unwritten.append((Term("offset", 0), "tau0", 0.125, "no MuJoCo joint field"))
    check.unwritten.append(("offset panda_joint1", 0.5))
    run = IdentifyRun(report, robot, base, tmp_path / "r.h5", [], mjcf=model, mujoco=check)
    console = Console(file=io.StringIO(), width=250)
    for item in mjcf_written(run):
        console.print(item)
    text = console.file.getvalue()
    loaded = mujoco.MjModel.from_xml_path(str(model.path))
    dof = loaded.joint("panda_joint3").dofadr[0]
    row = next(line for line in text.splitlines() if "panda_joint3" in line)
    assert f"{loaded.dof_frictionloss[dof]:.4g}" in row and f"{loaded.dof_damping[dof]:.4g}" in row
    assert f"{check.relative_mujoco[2]:.2f}" in row and f"{check.relative_excite[2]:.2f}" in row
    assert f"MuJoCo {check.relative_mujoco.mean():.2f} %" in text
    assert f"to {check.rigid:.1e} of the largest torque" in text and f"wrote {model.path}" in text
    assert "not in the MJCF (no MuJoCo joint field): offset panda_joint1 tau0 = 0.125, +0.50 points" in text
