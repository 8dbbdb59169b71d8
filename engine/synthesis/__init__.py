"""Synthesis of lip trajectories from timed targets: every method, the registry and the per-corpus choice."""
