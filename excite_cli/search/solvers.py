"""The nonlinear programming solvers behind ``optimizer.method``, one interface for all:

    minimize f(z) subject to g(z) ≤ 0,

z the optimizer's variables (:mod:`excite_cli.trajectory.boundary`), f the criterion (Eqs. 5, 16) and g the
stacked constraints, both with analytic gradients.

- ``SLSQP``: scipy's sequential quadratic programming with a BFGS Hessian (the paper's quasi-Newton
  method with constraints, Section IV-A);
- ``trust-constr``: scipy's trust-region interior point method with BFGS Hessians;
- ``ipopt``: IPOPT's interior point method with a limited-memory BFGS Hessian, through cyipopt (the
  solver of FIGAROH, RAPTOR and FloBaRoID for this problem).

Every method sees the criterion scaled by :func:`criterion_scale` at its start. A quasi-Newton method
starts from the Hessian I, so its first step is the gradient itself; and SLSQP's merit function
charges a constraint nothing before its multiplier is known, so that first step is not held back by
any constraint that is not yet active. Unscaled (log det's gradient has components of 1-3 in the
variables, which are the joints' half-ranges), the first step doubled the motion: on a UR10 it drove
two capsules 19 cm into each other, where their distance has no useful gradient (the segments cross),
SLSQP's linearized constraints became inconsistent and 4 of 6 restarts ended in "More than 3*n
iterations in LSQ subproblem" at or near their start. Scaled, none did (bench/robustness.py).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Optional, Protocol

import numpy as np
from scipy.optimize import BFGS, NonlinearConstraint, minimize

from excite_cli.errors import ExciteError
from excite_cli.memo import once
from excite_cli.search.screening import screened

#: The methods of ``optimizer.method``.
METHODS = ("SLSQP", "trust-constr", "ipopt")

#: Called with each accepted iterate z of the solver; raising StopIteration ends the run there.
IterateHook = Callable[[np.ndarray], None]
#: The largest component [1] of the scaled criterion's gradient at the start: a first step along it
#: moves no joint's q, q̇ or q̈ by more than a tenth of its half-range (the variables are scaled so
#: that 1 is a half-range, :meth:`~excite_cli.constraints.joint_limits.JointLimits.coefficient_scale`).
FIRST_STEP = 0.1


class NLP(Protocol):
    """The problem a solver sees: f(z) and its gradient (z.size,), g(z) (m,) and its Jacobian
    (m, z.size), each asked for on its own (a line search's trial points need values only)."""

    def value(self, z: np.ndarray) -> float: ...

    def gradient(self, z: np.ndarray) -> np.ndarray: ...

    def constraint_values(self, z: np.ndarray) -> np.ndarray: ...

    def constraint_jacobian(self, z: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class SolverRun:
    """How a solver ended.

    Attributes:
        z: its last iterate (may violate g ≤ 0).
        iterations: its iterations.
        message: its own message.
        limit: it stopped at its iteration limit.
        failed: it stopped on a failure of its own (line search, incompatible subproblem,
            restoration), not at a limit and not on its convergence test.
        scale: the factor [1] the solver's criterion was multiplied by (:func:`criterion_scale`).
    """

    z: np.ndarray
    iterations: int
    message: str
    limit: bool
    failed: bool
    scale: float = 1.0


def criterion_scale(gradient: np.ndarray) -> float:
    """The factor [1] the criterion is multiplied by for the solver: ``FIRST_STEP`` over the largest
    component of its gradient (n_z,) at the start (1 for a zero gradient)."""
    largest = float(np.abs(gradient).max(initial=0.0))
    return FIRST_STEP / largest if largest > 0.0 and np.isfinite(largest) else 1.0


class _ScaledCriterion:
    """``nlp`` with its criterion (value and gradient) multiplied by ``scale``, or by
    :func:`criterion_scale` of its gradient at z0 (n_z,), which is handed back when the solver asks
    for it; constraints as they are."""

    def __init__(self, nlp: NLP, z0: np.ndarray, scale: Optional[float] = None):
        self.nlp = nlp
        self.scale = criterion_scale(self._gradient(z0)) if scale is None else scale
        self.constraint_values, self.constraint_jacobian = nlp.constraint_values, nlp.constraint_jacobian

    def value(self, z: np.ndarray) -> float:
        return self.scale * self.nlp.value(z)

    def gradient(self, z: np.ndarray) -> np.ndarray:
        return self.scale * self._gradient(z)

    def _gradient(self, z: np.ndarray) -> np.ndarray:
        """The nlp's gradient, once per point: the one at z0 that sets the scale is the solver's first."""
        return once(self, "gradient", z, lambda: self.nlp.gradient(z))


def solve(
    method: str,
    nlp: NLP,
    z0: np.ndarray,
    max_iterations: int,
    tolerance: float,
    on_iterate: IterateHook,
    scale: Optional[float] = None,
) -> SolverRun:
    """Run ``method`` (one of ``METHODS``) from z0 (n_z,) for at most ``max_iterations`` iterations, on
    the criterion scaled by :func:`criterion_scale` at z0 (module docstring), or by ``scale``.

    Args:
        tolerance: the solver's own convergence tolerance (SLSQP ``ftol``, trust-constr ``gtol``,
            IPOPT ``tol``) on the criterion as given: the solver gets it scaled as the criterion is.
        on_iterate: called with every accepted iterate.
        scale: the scale of a run this one continues (:attr:`SolverRun.scale`). Rescaled at a point
            near its optimum, where the criterion's gradient is small, the first step of a fresh
            quasi-Newton matrix is as long as a start's (``FIRST_STEP``) and leaves the optimum:
            on the G1 with A-optimality, 2 of 3 kept restarts polished this way ended stalled.

    Raises:
        ExciteError: an unknown method, or ``ipopt`` without cyipopt installed.
    """
    methods = {"SLSQP": _slsqp, "trust-constr": _trust_constr, "ipopt": _ipopt}
    if method not in methods:
        raise ExciteError("optimizer.method", f"unknown '{method}', expected one of {', '.join(METHODS)}")
    scaled = _ScaledCriterion(nlp, z0, scale)
    seen = screened(scaled, z0) if method == "SLSQP" else scaled  # its QP's cost grows with the rows
    run = methods[method](seen, z0, max_iterations, tolerance * scaled.scale, on_iterate)
    return replace(run, scale=scaled.scale)


def _slsqp(nlp: NLP, z0: np.ndarray, max_iterations: int, tolerance: float, on_iterate: IterateHook) -> SolverRun:
    result = minimize(
        nlp.value,
        z0,
        jac=nlp.gradient,
        method="SLSQP",
        constraints=[
            {"type": "ineq", "fun": lambda z: -nlp.constraint_values(z), "jac": lambda z: -nlp.constraint_jacobian(z)}
        ],
        options={"maxiter": max_iterations, "ftol": tolerance},
        callback=lambda z, *_: on_iterate(z),
    )
    # scipy's SLSQP exit modes: 0 converged (ftol), 9 iteration limit, 99 stopped by on_iterate, others failures
    return SolverRun(
        result.x, int(result.nit), str(result.message), result.status in (9, 99), result.status not in (0, 9, 99)
    )


def _trust_constr(
    nlp: NLP, z0: np.ndarray, max_iterations: int, tolerance: float, on_iterate: IterateHook
) -> SolverRun:
    constraint = NonlinearConstraint(nlp.constraint_values, -np.inf, 0.0, jac=nlp.constraint_jacobian, hess=BFGS())
    result = minimize(
        nlp.value,
        z0,
        jac=nlp.gradient,
        hess=BFGS(),
        method="trust-constr",
        constraints=[constraint],
        options={"maxiter": max_iterations, "gtol": tolerance, "xtol": 1e-10},
        callback=lambda z, *_: on_iterate(z),
    )
    # trust-constr's status: 0 iteration limit, 1 gtol met, 2 xtol met (steps too small), 3 stopped by on_iterate
    return SolverRun(result.x, int(result.nit), str(result.message), result.status in (0, 3), False)


def _ipopt(nlp: NLP, z0: np.ndarray, max_iterations: int, tolerance: float, on_iterate: IterateHook) -> SolverRun:
    try:
        import cyipopt
    except ImportError:
        raise ExciteError(
            "optimizer.method",
            "'ipopt' needs cyipopt, which `make install` builds against Debian's "
            "coinor-libipopt-dev (see the Makefile's ipopt target)",
        ) from None
    last, count = [z0], [0]

    class _Callbacks:
        def objective(self, z):
            last[0] = z
            return nlp.value(z)

        def gradient(self, z):
            return nlp.gradient(z)

        def constraints(self, z):
            return nlp.constraint_values(z)

        def jacobian(self, z):
            return nlp.constraint_jacobian(z).ravel()

        def intermediate(self, _mode, iteration, *_):
            if iteration > 0:  # IPOPT evaluates f last at the trial point it accepts
                count[0] = iteration
                try:
                    on_iterate(last[0])
                except StopIteration:
                    return False  # IPOPT's User_Requested_Stop (5)
            return True

    m = nlp.constraint_values(z0).size
    problem = cyipopt.Problem(
        n=z0.size, m=m, problem_obj=_Callbacks(), lb=None, ub=None, cl=np.full(m, -1e20), cu=np.zeros(m)
    )
    for option, value in (
        ("hessian_approximation", "limited-memory"),
        ("max_iter", max_iterations),
        ("tol", tolerance),
        ("print_level", 0),
        ("sb", "yes"),
    ):
        problem.add_option(option, value)
    z, info = problem.solve(z0)
    status = int(info["status"])
    message = info["status_msg"].decode() if isinstance(info["status_msg"], bytes) else str(info["status_msg"])
    # IPOPT's status: 0 solved, 1 solved to an acceptable level, -1 iteration limit, 5 stopped by on_iterate,
    # others failures
    return SolverRun(np.asarray(z), count[0], message, status in (-1, 5), status not in (0, 1, -1, 5))
