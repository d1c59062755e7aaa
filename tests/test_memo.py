"""One-point memos: computed once per point and name, again at a new point or shape."""

import numpy as np

from excite_cli.memo import once


class Owner:
    pass


def test_a_computation_runs_once_per_point_and_again_at_a_new_one():
    owner, calls = Owner(), []

    def compute(x):
        calls.append(x.copy())
        return float(x.sum())

    x = np.arange(4.0)
    assert once(owner, "sum", x, lambda: compute(x)) == 6.0
    assert once(owner, "sum", x.copy(), lambda: compute(x)) == 6.0  # equal values: not again
    assert len(calls) == 1
    y = x + 1.0
    assert once(owner, "sum", y, lambda: compute(y)) == 10.0
    assert once(owner, "sum", x, lambda: compute(x)) == 6.0  # one point held: x again is computed again
    assert len(calls) == 3


def test_names_owners_and_shapes_are_apart():
    a, b = Owner(), Owner()
    x = np.arange(6.0)
    assert once(a, "first", x, lambda: 1) == 1
    assert once(a, "second", x, lambda: 2) == 2  # another name at the same point
    assert once(b, "first", x, lambda: 3) == 3  # another owner
    assert once(a, "first", x.reshape(2, 3), lambda: 4) == 4  # the same bytes in another shape
    assert once(a, "first", x.astype(np.float32), lambda: 5) == 5  # another dtype
