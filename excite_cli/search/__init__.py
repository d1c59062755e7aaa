"""How a design is searched: the nonlinear program and its solvers, the KKT test, one restart, the
restarts of an iteration, the sequential generation, where the work runs, and the random baseline."""
