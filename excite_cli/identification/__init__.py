"""Closing the loop on measured data: measurements, preprocessing, candidate effects, identification."""
