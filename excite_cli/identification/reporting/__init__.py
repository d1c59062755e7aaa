"""Reporting: the identify report as one record, its HDF5 file, the identified URDF."""
