"""Choosing the model: cross-validation folds, the stepwise effect search, the fit chosen with the model."""
