"""The joint trajectories: finite Fourier series (Eqs. 48–49) and their boundary conditions (Eq. 50)."""
