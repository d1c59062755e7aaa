"""Constraints on the Fourier coefficients α: each gives values g(α) ≤ 0 and their Jacobian."""

from excite_cli.constraints.constraint import Constraint, FineCheck
from excite_cli.constraints.joint_limits import JointLimits

__all__ = ["Constraint", "FineCheck", "JointLimits"]
