"""Constraints on the Fourier coefficients α: each gives values g(α) ≤ 0 and their Jacobian."""

from excite_cli.constraints.com_region import ComRegion
from excite_cli.constraints.constraint import Constraint, FineCheck, accepted, farthest_accepted
from excite_cli.constraints.joint_limits import JointLimits
from excite_cli.constraints.self_collision import SelfCollision

__all__ = ["ComRegion", "Constraint", "FineCheck", "JointLimits", "SelfCollision", "accepted", "farthest_accepted"]
