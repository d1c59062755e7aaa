"""Measured runs: files and ROS bags read, joints mapped, a known payload, preprocessing (resampling,
zero-phase filtering, differentiation)."""
