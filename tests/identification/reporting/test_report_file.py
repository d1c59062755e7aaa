"""The identify report: its effect values in order with their coefficient names, its HDF5 file read
back, and the identified URDF that pinocchio loads with the consistent fit's torques."""

from dataclasses import replace

import h5py
import numpy as np
import pinocchio as pin
from conftest import rows_copy

from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.h5 import read_strings
from excite_cli.identification.reporting.report import Report
from excite_cli.identification.reporting.report_file import write_identification
from excite_cli.identification.reporting.urdf_out import merged_links, urdf_deviation, write_urdf


def test_effect_values_name_every_coefficient_in_the_order_of_the_fit(simulated_identification):
    _, report, *_ = simulated_identification
    assert isinstance(report, Report)
    values = report.effect_values()
    b = len(report.base_names)
    assert [v for _, _, v, _ in values] == report.selection.fit.x[b:].tolist()
    assert {name for _, name, _, _ in values} == {"Fc", "Fv"}
    coulomb = [v for t, name, v, _ in values if name == "Fc"]
    np.testing.assert_allclose(coulomb, 0.6, rtol=0.02)  # the simulated runs' Coulomb friction


def test_the_report_file_reads_back_what_the_report_holds(simulated_identification, tmp_path):
    problem, report, robot, base, regressor = simulated_identification
    path = tmp_path / "report.h5"
    write_identification(path, report, robot, base, problem, rows_copy(regressor))  # it empties what it writes
    with h5py.File(path) as f:
        g = f["identification"]
        assert read_strings(g, "base_parameter_names") == report.base_names
        assert read_strings(f["robot"], "base_independent_parameters") == [
            robot.parameter_names[k] for k in base.independent
        ]
        np.testing.assert_array_equal(f["robot/regrouping_matrix"][()], base.regrouping)
        rows = g["effects"][()]
        assert [float(v) for v in rows["value"]] == [v for _, _, v, _ in report.effect_values()]
        np.testing.assert_array_equal(f["regressor"][()], np.vstack(regressor.regressor))  # in slices, fit first


def test_the_identified_urdf_loads_and_reproduces_the_consistent_torques(simulated_identification, tmp_path):
    problem, report, robot, base, _ = simulated_identification
    assert "panda_link7" in merged_links(robot)  # the hand and fingers are folded into link 7's body
    target = tmp_path / "identified.urdf"
    source = tmp_path / "source.urdf"
    source.write_bytes(resolve_urdf(problem.robot, problem.folder)[0].read_bytes())
    effects = [(t.effect, c, report.joints[t.joint], v) for t, c, v, _ in report.effect_values(consistent=True)]
    write_urdf(source, target, robot, report.consistent.standard, effects, "test")
    model = pin.buildModelFromUrdf(str(target))
    assert model.nq >= robot.n_joints
    phi = report.consistent.bodies_base  # what a URDF holds: the rotors are comments in it

    def identified(q, qd, qdd):
        return robot.regressor(q, qd, qdd) @ base.composition_matrix @ phi

    assert urdf_deviation(problem.robot, robot, identified, target, samples=20) < 1e-6


def test_a_model_without_effect_columns_writes_an_empty_effect_regressor(simulated_identification, tmp_path):
    """A chosen model that the design holds no column of (no effects, or only asymmetric ones) gave h5py
    zero-width chunks: a traceback after the whole fit, and no report."""
    problem, report, robot, base, regressor = simulated_identification
    rows = rows_copy(regressor)
    rows = replace(rows, effects=[part[:, :0] for part in rows.effects], effect_names=[])
    write_identification(tmp_path / "report.h5", report, robot, base, problem, rows)
    with h5py.File(tmp_path / "report.h5") as f:
        assert f["effect_regressor"].shape == (f["regressor"].shape[0], 0)
