"""MuJoCo's check of the written MJCF on the shipped simulated runs (Coulomb 0.6 Nm and viscous
0.4 Nm·s/rad on every joint): its inverse dynamics is excite's model, its validation error excite's
within 1 point, the report records it, and a file that is not the identified model fails the check."""

import h5py
import numpy as np
from conftest import rows_copy

from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.identification.reporting.mjcf_check import check_mjcf
from excite_cli.identification.reporting.mjcf_out import write_mjcf
from excite_cli.identification.reporting.report_file import write_identification


def _write(simulated_identification, target):
    problem, report, robot, *_ = simulated_identification
    urdf, dirs = resolve_urdf(problem.robot, problem.folder)
    effects = [(t, c, v) for t, c, v, _ in report.effect_values(consistent=True)]
    return write_mjcf(urdf, dirs, robot, {}, report.consistent.standard, effects, target)


def test_mujoco_reproduces_the_identified_model_and_its_validation_error(simulated_identification, tmp_path):
    problem, report, robot, base, regressor = simulated_identification
    model = _write(simulated_identification, tmp_path / "panda.xml")
    assert {a for _, a in model.fields} <= {"damping", "frictionloss", "armature"} and model.unwritten == []
    # the rotors the consistent fit holds apart from the bodies are their joints' armature
    assert {j for j, a in model.fields if a == "armature"} == set(report.consistent.rotor_joints) != set()
    check = check_mjcf(problem, report, robot, base, model)
    assert check.rigid <= 1e-5 and check.friction <= 1e-5
    np.testing.assert_allclose(check.relative_excite, report.relative_consistent, rtol=1e-12)
    np.testing.assert_allclose(check.relative_written, report.relative_consistent, rtol=1e-12)  # all written
    assert abs(check.relative_mujoco.mean() - check.relative_excite.mean()) <= 1.0
    assert check.friction_differs < 20.0
    path = tmp_path / "report.h5"
    write_identification(path, report, robot, base, problem, rows_copy(regressor), model, check)
    with h5py.File(path) as f:
        g = f["mujoco"]
        assert g.attrs["mjcf"] == str(model.path) and g.attrs["rigid_deviation"] == check.rigid
        np.testing.assert_array_equal(g["validation_mujoco"][()], check.relative_mujoco)
        fields = g["joint_fields"][()]
        assert len(fields) == 14 + len(report.consistent.rotor_joints) and len(g["not_in_mjcf"]) == 0
        assert np.all(fields["value"] >= 0)


def test_a_file_that_is_not_the_identified_model_fails_the_check(simulated_identification, tmp_path):
    problem, report, robot, base, _ = simulated_identification
    model = _write(simulated_identification, tmp_path / "panda.xml")
    text = model.path.read_text()
    mass = text[text.index('mass="', text.index('name="panda_link3"')) :].split('"')[1]
    model.path.write_text(text.replace(f'mass="{mass}"', f'mass="{float(mass) * 1.01:g}"', 1))
    assert check_mjcf(problem, report, robot, base, model).rigid > 1e-4
    model.fields[("panda_joint1", "frictionloss")] *= 1.1  # what excite holds is not what was written
    model.path.write_text(text)
    check = check_mjcf(problem, report, robot, base, model)
    assert check.rigid <= 1e-5 and check.friction > 1e-4  # 0.06 Nm of some 60 Nm
