"""Collision geometry: the URDF's shapes and the capsules fitted to them (Eq. 53)."""
