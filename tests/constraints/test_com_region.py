"""The centre-of-mass region (Eq. 52) as a polygon: holds inside, fails outside, Jacobian by differences."""

import numpy as np
from conftest import CONFIGS

from excite_cli.config_file import load_problem
from excite_cli.constraints.com_region import ComRegion
from excite_cli.design.resolve import build_excitation
from excite_cli.design.verify import constraint_jacobian_error


def test_com_polygon_region():
    excitation = build_excitation(load_problem(CONFIGS / "panda_joint_limits.yaml"))
    robot = excitation.robot
    com = robot.com(excitation.home)[0][:2]
    square = lambda half: com + half * np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]])  # noqa: E731
    alpha = excitation.limits.random_start(
        excitation.trajectory.n_coefficients, np.random.default_rng(1), 0.5, excitation.home
    )
    excursion = np.abs(np.array([robot.com(q)[0][:2] for q in excitation.grid_basis.evaluate(alpha)[0]]) - com).max()
    wide = ComRegion(robot, excitation.grid_basis, com, polygon=square(2.0 * excursion))
    narrow = ComRegion(robot, excitation.grid_basis, com, polygon=square(0.5 * excursion))
    assert (
        wide.check(alpha, excitation.grid_basis).max_violation
        < 0
        < narrow.check(alpha, excitation.grid_basis).max_violation
    )
    assert constraint_jacobian_error(narrow, alpha) < 1e-6
