"""One contract for every constraint class and every criterion, as crocoddyl checks each model family:
value and Jacobian (gradient) against central differences at a lively random point, shapes, the
cached values equal to a fresh evaluation, the fine-grid recheck's figures, names and words. Two
small problems register every constraint class (the G1 arms standing: joint limits, CoM region,
zero-moment point, self-collision; a Panda on its table: torque limits, minimum torque use, the
world, self-collision); a class nobody registers fails the test, and so does a perturbed Jacobian."""

import dataclasses

import numpy as np
import pytest
import yaml
from conftest import CONFIGS, write_config

from excite_cli.config_file import load_problem
from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.criteria import NAMES
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import check_gradient, constraint_jacobian_error
from excite_cli.plots.tracks import PANELS, Drawn

SMALL = {"harmonics": 3, "cost_samples": 10, "cost_period": 0.8, "constraint_period": 0.1}


def _excitation(tmp_path_factory, config: str, **limits):
    data = yaml.safe_load((CONFIGS / config).read_text())
    data["trajectory"].update(SMALL)
    data["limits"].update(limits)
    return build_excitation(load_problem(write_config(tmp_path_factory.mktemp(config), data)))


@pytest.fixture(scope="module")
def problems(tmp_path_factory):
    return [
        _excitation(tmp_path_factory, "g1_arms.yaml"),
        _excitation(tmp_path_factory, "panda.yaml", min_torque_use=0.05),
    ]


def _lively(excitation, seed: int = 1) -> np.ndarray:
    return excitation.limits.random_start(
        excitation.trajectory.n_coefficients, np.random.default_rng(seed), 0.9, excitation.home
    )


def _classes(root: type) -> set[type]:
    """``root`` and its subclasses that the package defines (tests define their own)."""
    found = {c for sub in root.__subclasses__() for c in _classes(sub)}
    return found | ({root} if root.__module__.startswith("excite_cli.") else set())


def _registered(problems) -> list[tuple[object, Constraint]]:
    return [(e, c) for e in problems for c in [e.limits, *e.constraints]]


def test_every_constraint_class_is_registered_by_the_contract_problems(problems):
    seen = {type(c) for _, c in _registered(problems)}
    assert _classes(Constraint) - {Constraint} <= seen, _classes(Constraint) - seen


def test_every_constraint_keeps_the_contract(problems):
    for excitation, c in _registered(problems):
        alpha = _lively(excitation)
        g, J = c.evaluate(alpha)
        assert g.ndim == 1 and J.shape == (g.size, alpha.size), c.name
        fresh = type(c).values(c, alpha + 0.0)  # values alone may take a cheaper path: the same to rounding
        np.testing.assert_allclose(fresh, g, rtol=1e-12, atol=1e-12, err_msg=c.name)
        np.testing.assert_array_equal(c.jacobian(alpha), J)
        assert np.all(np.isfinite(g)) and np.all(np.isfinite(J)), c.name
        assert constraint_jacobian_error(c, alpha) < 1e-5, c.name
        fine = c.check(alpha, excitation.fine_basis)
        assert isinstance(fine, FineCheck) and np.isfinite(fine.max_violation), c.name
        assert all(isinstance(v, (float, int, str)) for v in fine.details.values()), c.name
        assert c.name and c.field and c.in_words(), c.name
        assert set(c.drawn()) <= {f.name for f in dataclasses.fields(Drawn)}, c.name
        assert set(c.track(alpha, excitation.grid_basis)) <= set(PANELS), c.name  # every track has its panel
        Q = excitation.trajectory.basis(np.linspace(0.0, 1.0, 5)).evaluate(alpha)[0]
        for pair, distance in c.never_apart(Q, 0.05):
            assert len(pair) == 2 and distance < 0.05, c.name
        assert all(isinstance(link, str) and margin >= 0 for link, margin in c.always_within(Q)), c.name


def test_a_perturbed_jacobian_row_breaks_the_contract(problems):
    excitation, c = _registered(problems)[1]
    alpha = _lively(excitation)
    g, J = c.evaluate(alpha)
    wrong = J.copy()
    wrong[np.argmax(np.abs(J).sum(axis=1))] *= 1.01

    class Perturbed(type(c)):
        def evaluate(self, a):
            values, jacobian = super().evaluate(a)
            return values, (wrong if np.array_equal(a, alpha) else jacobian)

    perturbed = object.__new__(Perturbed)
    perturbed.__dict__.update(c.__dict__)
    assert constraint_jacobian_error(perturbed, alpha) > 1e-4


@pytest.mark.parametrize("objective", NAMES)
def test_every_criterion_s_gradient_matches_central_differences(problems, objective):
    excitation = problems[1]
    check = check_gradient(excitation.criterion(objective=objective), _lively(excitation, 2), repeats=1)
    assert check.error_central < 1e-6, objective
