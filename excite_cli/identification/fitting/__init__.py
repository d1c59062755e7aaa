"""Fitting: the dataset of base-regressor and effect columns, normal equations kept per joint, least
squares, the physically consistent fit."""
