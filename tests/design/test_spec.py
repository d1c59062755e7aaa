"""A design resolved once: the spec pickles, builds the excitation the config builds, keeps its frame
read-only, and what is changed in it (not in the config) is what a build from it uses."""

import dataclasses
import pickle

import numpy as np
import pytest
import yaml
from conftest import CONFIGS, small

from excite_cli.config_file import load_problem
from excite_cli.design.excitation import build_design
from excite_cli.design.resolve import build_excitation, resolve
from excite_cli.design.spec import needs_collision


@pytest.fixture(scope="module")
def problem():
    return small(load_problem(CONFIGS / "panda_joint_limits.yaml"))


def test_a_spec_built_in_another_process_is_the_excitation_of_its_config(problem):
    spec, robot = resolve(problem)
    assert robot.n_joints == 7 and spec.columns == spec.base.count  # no effects: the rigid body's columns
    again = build_design(pickle.loads(pickle.dumps(spec)))  # as a worker gets it: its own robot
    direct = build_excitation(problem)
    alpha = direct.random_start(np.random.default_rng(0))
    np.testing.assert_array_equal(again.scaled_frame, direct.scaled_frame)
    assert again.base.names == direct.base.names
    assert again.criterion().value(alpha) == direct.criterion().value(alpha)
    assert [c.name for c in again.constraints] == [c.name for c in direct.constraints]
    # what the result file stores: the config as run, its own text and where it was read from
    assert yaml.safe_load(spec.config.effective)["trajectory"]["harmonics"] == 4  # small()'s, not the file's
    assert spec.config.original == problem.source_text and spec.config.path.endswith("panda_joint_limits.yaml")


def test_the_robot_loads_its_collision_geometry_only_for_the_constraints_that_need_it(problem):
    assert not needs_collision(problem.constraints)  # joint limits only
    g1 = load_problem(CONFIGS / "g1_arms.yaml").constraints
    assert needs_collision(g1)  # capsules and the soles' contact points
    assert needs_collision(
        g1.model_copy(update={"self_collision": None, "environment": None, "com": None})
    )  # the ZMP's
    assert not needs_collision(
        g1.model_copy(update={"self_collision": None, "environment": None, "com": None, "zmp": None})
    )


def test_the_frame_is_read_only_and_a_frame_changed_in_the_spec_is_the_one_built(problem):
    spec, robot = resolve(problem)
    with pytest.raises(ValueError):
        spec.scaled_frame[0, 0] = 2.0
    emphasis = np.linspace(0.5, 2.0, spec.columns)
    changed = build_design(dataclasses.replace(spec, scaled_frame=spec.scaled_frame * emphasis), robot)
    plain = build_design(spec, robot)
    np.testing.assert_array_equal(changed.scaled_frame, spec.scaled_frame * emphasis)
    alpha = plain.random_start(np.random.default_rng(1))
    C = plain.criterion(scaling="none").regressor(alpha)
    # log det of C L: the frame adds 2 log det L, with the criterion's sign and scale (1/b)
    shift = changed.criterion(scaling="urdf", objective="log_det").value(alpha) - plain.criterion(
        scaling="urdf", objective="log_det"
    ).value(alpha)
    assert shift == pytest.approx(-2.0 * np.log(emphasis).sum() / spec.columns, rel=1e-9)
    assert np.linalg.matrix_rank(C) == spec.columns
