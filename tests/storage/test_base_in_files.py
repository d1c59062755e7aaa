"""The base parameters travel with the data: every file stores them, every reader checks them by name,
takes columns in another order, and refuses other base parameters in one line."""

import h5py
import numpy as np
import pytest
from conftest import CONFIGS

from excite_cli.config_file import load_problem
from excite_cli.design.resolve import build_excitation
from excite_cli.errors import ExciteError
from excite_cli.h5 import read_strings, write_strings
from excite_cli.search.sequence import describe
from excite_cli.storage.results import read_iterations, write_result
from excite_cli.stored.prior import prior_rows, read_prior_file


@pytest.fixture(scope="module")
def excitation():
    return build_excitation(load_problem(CONFIGS / "smoke.yaml"))


@pytest.fixture(scope="module")
def rows(excitation):
    return excitation.criterion().regressor(excitation.random_start(np.random.default_rng(0)))


def _prior_file(path, rows, names):
    with h5py.File(path, "w") as f:
        f["regressor"] = rows
        write_strings(f.create_group("robot"), "base_parameter_names", names)
    return path


def test_prior_columns_in_another_order_are_mapped_by_name(tmp_path, excitation, rows):
    base = excitation.base
    order = np.random.default_rng(1).permutation(base.count)
    path = _prior_file(tmp_path / "prior.h5", rows[:, order], [base.names[k] for k in order])
    np.testing.assert_array_equal(prior_rows(read_prior_file(path), base), rows)


def test_prior_of_other_base_parameters_is_refused_by_name(tmp_path, excitation, rows):
    names = list(excitation.base.names)
    names[3] = "Izz_panda_link9 + 1·m_panda_link1"
    path = _prior_file(tmp_path / "prior.h5", rows, names)
    with pytest.raises(ExciteError) as caught:
        prior_rows(read_prior_file(path), excitation.base)
    assert caught.value.field == "sequence.prior" and "Izz_panda_link9" in str(caught.value)


def test_a_result_stores_its_base_and_resume_refuses_another(tmp_path, excitation):
    path = tmp_path / "result.h5"
    result = describe(
        excitation, 1, excitation.random_start(np.random.default_rng(2)), np.zeros((0, excitation.base.count))
    )
    write_result(path, excitation, [result], 0)
    with h5py.File(path) as f:
        stored = read_strings(f["robot"], "base_independent_parameters")
        names = read_strings(f["robot"], "base_parameter_names")
        np.testing.assert_array_equal(f["robot/regrouping_matrix"][()], excitation.base.regrouping)
    assert stored == [excitation.robot.parameter_names[k] for k in excitation.base.independent]
    assert names == excitation.base.names
    assert read_iterations(path, excitation)[0].cond_stacked == result.cond_stacked
    with h5py.File(path, "a") as f:
        del f["robot/base_parameter_names"]
        write_strings(f["robot"], "base_parameter_names", names[::-1][:-1] + ["mx_panda_link0"])
    with pytest.raises(ExciteError) as caught:
        read_iterations(path, excitation)
    assert caught.value.field == "resume" and "mx_panda_link0" in str(caught.value)


def test_a_prior_with_effect_columns_enters_only_a_design_with_the_same_effects(tmp_path, excitation, rows):
    base, effects = excitation.base, ["Fc_panda_joint1", "Fv_panda_joint1"]
    wide = np.hstack([rows, np.ones((rows.shape[0], 2))])
    path = _prior_file(tmp_path / "prior.h5", wide, base.names)
    with h5py.File(path, "a") as f:
        write_strings(f["robot"], "effect_names", effects)
    np.testing.assert_array_equal(prior_rows(read_prior_file(path), base, effects), wide)
    for other in ([], ["Fc_panda_joint1"], effects[::-1]):
        with pytest.raises(ExciteError, match=r"effect columns \[Fc_panda_joint1, Fv_panda_joint1\]"):
            prior_rows(read_prior_file(path), base, other)
    rigid = _prior_file(tmp_path / "rigid.h5", rows, base.names)
    with pytest.raises(ExciteError, match=r"effect columns \[\]; this design has \[Fc_panda_joint1"):
        prior_rows(read_prior_file(rigid), base, effects)
