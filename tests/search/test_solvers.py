"""Every method of optimizer.method on a problem whose optimum is known: the nearest point of a disc
to an outside point, min |z − a|² s.t. |z|² ≤ 1, optimum a/|a|, multiplier |a| − 1."""

import numpy as np
import pytest

from excite_cli.errors import ExciteError
from excite_cli.search.solvers import METHODS, solve


class Disc:
    """The NLP protocol of the solvers, with evaluation counts."""

    def __init__(self, target):
        self.target, self.calls = np.asarray(target, dtype=float), {"value": 0, "gradient": 0}

    def value(self, z):
        self.calls["value"] += 1
        return float((z - self.target) @ (z - self.target))

    def gradient(self, z):
        self.calls["gradient"] += 1
        return 2.0 * (z - self.target)

    def constraint_values(self, z):
        return np.array([z @ z - 1.0])

    def constraint_jacobian(self, z):
        return 2.0 * z[None, :]


@pytest.mark.parametrize("method", METHODS)
def test_each_method_finds_the_nearest_point_of_the_disc(method):
    if method == "ipopt":
        pytest.importorskip("cyipopt")
    nlp, seen = Disc([3.0, 4.0]), []
    run = solve(method, nlp, np.zeros(2), 200, 1e-10, seen.append)
    np.testing.assert_allclose(run.z, [0.6, 0.8], atol=1e-5)
    assert not run.failed and 0 < run.iterations <= 200 and len(seen) >= 1
    assert nlp.calls["gradient"] <= nlp.calls["value"] + 1  # gradients only where the solver needs them


def test_an_iteration_limit_is_reported_as_such():
    run = solve("SLSQP", Disc([3.0, 4.0]), np.array([-0.9, 0.1]), 1, 1e-12, lambda z: None)
    assert run.limit and not run.failed and run.iterations == 1


def test_an_unknown_method_is_named():
    with pytest.raises(ExciteError, match="optimizer.method"):
        solve("newton", Disc([1.0, 1.0]), np.zeros(2), 10, 1e-6, lambda z: None)


@pytest.mark.parametrize("units", [1e-3, 1.0, 1e4])
def test_the_criterion_scale_makes_slsqp_blind_to_the_criterion_units(units):
    """The disc problem's criterion in other units (× 1e-3 … 1e4) has the same optimum a/|a|; with the
    criterion scaled at the start, SLSQP takes the same steps in every unit: the same iterates."""
    reference, scaled = [], []
    solve("SLSQP", Disc([3.0, 4.0]), np.array([0.1, -0.2]), 200, 1e-12, reference.append)

    class Units(Disc):
        def value(self, z):
            return units * super().value(z)

        def gradient(self, z):
            return units * super().gradient(z)

    run = solve("SLSQP", Units([3.0, 4.0]), np.array([0.1, -0.2]), 200, 1e-12 * units, scaled.append)
    np.testing.assert_allclose(run.z, [0.6, 0.8], atol=1e-6)
    np.testing.assert_allclose(np.array(scaled), np.array(reference), rtol=1e-6, atol=1e-9)


def test_the_first_step_moves_no_variable_more_than_first_step():
    """From far inside the disc towards a target 1000 away, the gradient's largest component is
    2000; SLSQP's first step (Hessian I) is the scaled gradient itself: FIRST_STEP in its largest
    component, not 2000 (which would leave the disc a thousand times over)."""
    from excite_cli.search.solvers import FIRST_STEP

    seen = []
    z0 = np.array([0.1, 0.0])
    solve("SLSQP", Disc([1000.1, 0.0]), z0, 1, 1e-12, seen.append)
    assert np.abs(seen[0] - z0).max() == pytest.approx(FIRST_STEP, rel=1e-6)


def test_a_continuation_keeps_the_scale_of_the_run_it_continues():
    """Near an optimum inside the disc the gradient is small; rescaled there, a fresh run's first step
    is FIRST_STEP long and leaves the optimum 100 × farther than it was; with the scale of the run it
    continues (set where the gradient was 0.8), its first step is that scale times the gradient."""
    from excite_cli.search.solvers import FIRST_STEP

    first = solve("SLSQP", Disc([0.3, 0.4]), np.zeros(2), 1, 1e-12, lambda z: None)
    assert first.scale == pytest.approx(FIRST_STEP / 0.8)
    near = np.array([0.301, 0.4])  # 1e-3 from the optimum, gradient (2e-3, 0)
    fresh, kept = [], []
    solve("SLSQP", Disc([0.3, 0.4]), near, 1, 1e-12, fresh.append)
    run = solve("SLSQP", Disc([0.3, 0.4]), near, 1, 1e-12, kept.append, first.scale)
    assert np.abs(fresh[0] - near).max() == pytest.approx(FIRST_STEP, rel=1e-6)
    assert np.abs(kept[0] - near).max() == pytest.approx(first.scale * 2e-3, rel=1e-6)
    assert run.scale == first.scale
