"""Sweeps: many runs of a grid of methods, tasks and seeds, on local processes (sweep) or on a Ray
cluster (ray_sweep)."""
