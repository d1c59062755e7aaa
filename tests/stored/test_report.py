"""One reader of an identify report: what it reads back is what the identification reported, a file
that is not a report is told apart, and its errors carry the field that named the file."""

import h5py
import numpy as np
import pytest

from excite_cli.errors import ExciteError
from excite_cli.identification.effects import Term
from excite_cli.identification.fitting.least_squares import predict
from excite_cli.stored.report import read_identify_report, read_report


def test_the_report_read_back_is_the_reported_model(simulated_identification, report_file):
    """Joints, base parameters, every effect once with its coefficient, the consistent fit's rotors with
    columns of their own after them, v_c and each joint's validation error: as the pipeline's report
    holds them, predicting its validation torques."""
    problem, report, robot, base, _ = simulated_identification
    stored = read_identify_report(report_file, "report")
    assert stored.joints == robot.joint_names and stored.base_names == base.names
    effects, rotors = stored.terms[: -stored.rotors], stored.terms[-stored.rotors :]
    assert {(effect, joint) for effect, joint, _, _ in effects} == {
        (kind, j) for j in robot.joint_names for kind in ("coulomb", "viscous")
    }
    assert report.fit_choice.is_consistent and stored.rotors == 5  # joints 1-2's rotors regroup into the base
    assert [(e, j) for e, j, _, _ in rotors] == [("armature", j) for j in robot.joint_names[2:]]
    assert stored.coefficients.size == len(stored.terms) and np.all(stored.coefficients[: len(effects)] > 0)
    assert np.all(stored.coefficients[len(effects) :] >= 0)
    terms = [Term(e, robot.joint_names.index(j)) for e, j, _, _ in stored.terms]
    x = np.concatenate([stored.base, stored.coefficients])
    np.testing.assert_allclose(predict(report.validation, x, terms), report.predicted_after, atol=1e-9)
    assert stored.coulomb_velocity == problem.identification.coulomb_velocity
    assert stored.rms_after.shape == (robot.n_joints,) and stored.rate > 0


def test_a_file_that_is_not_a_report_is_none_or_refused_under_its_field(optimized, tmp_path):
    assert read_report(optimized, "sequence.prior") is None
    with pytest.raises(ExciteError, match="is not an identify report") as error:
        read_identify_report(optimized, "effects.model")
    assert error.value.field == "effects.model"
    with h5py.File(tmp_path / "half.h5", "w") as f:
        f.create_group("identification")
    with pytest.raises(ExciteError, match="no /identification/effects") as error:
        read_report(tmp_path / "half.h5", "sequence.prior")
    assert error.value.field == "sequence.prior"


@pytest.mark.parametrize("column, value", [("effect", "friction"), ("joint", "elbow")])
def test_an_effect_or_joint_the_report_does_not_define_is_refused_naming_it(report_file, tmp_path, column, value):
    """A damaged effects table (an effect excite does not know, a joint not among the report's) is one
    message under the field that named the file, not a KeyError later."""
    path = tmp_path / "edited.h5"
    path.write_bytes(report_file.read_bytes())
    with h5py.File(path, "a") as f:
        rows = f["identification/effects"][()]
        rows[column][0] = value
        del f["identification/effects"]
        f["identification/effects"] = rows
    with pytest.raises(ExciteError, match=f"names the {column} '{value}'") as error:
        read_report(path, "effects.model")
    assert error.value.field == "effects.model"


@pytest.mark.parametrize("damage, expected", [("rotor_joints", "names 0 of 7 rotors"), ("rotor_inertias", "missing")])
def test_a_damaged_rotor_list_is_refused_naming_it(report_file, tmp_path, damage, expected):
    """The consistent fit's rotors read back (a report whose reported fit is consistent) without their
    names or inertias: one message under the field that named the file, not a KeyError."""
    path = tmp_path / "edited.h5"
    path.write_bytes(report_file.read_bytes())
    with h5py.File(path, "a") as f:
        assert f["identification/physically_consistent"][()] and f["identification/rotor_own_columns"][()].size == 7
        del f[f"identification/{damage}"]
    with pytest.raises(ExciteError, match=expected) as error:
        read_report(path, "report")
    assert error.value.field == "report"
