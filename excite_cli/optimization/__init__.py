"""Designing persistently exciting trajectories: criterion, solvers, restarts, the sequence, the
random baseline, playback."""
