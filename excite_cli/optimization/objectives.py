"""The names of the optimizer's criteria, without what computes them (the command line's help lists
them at start-up; :mod:`~excite_cli.optimization.criterion` computes them)."""

#: The criteria of ``optimizer.objective``: the condition number (Eq. 5) or its log, D-optimality
#: (−log det(CᵀC) / b, the mean log eigenvalue of the information matrix, maximized),
#: E-optimality (−log σ_min(C), the smallest singular value maximized), after the paper's ref. [20],
#: and A-optimality (½ log(tr((CᵀC)⁻¹) / b), the log of the RMS of 1/σ_i: least squares' RMS parameter
#: error per unit of torque noise, minimized; Pukelsheim, Optimal Design of Experiments, 1993).
OBJECTIVES = ("cond", "log_cond", "log_det", "sigma_min", "log_trace_inverse")
