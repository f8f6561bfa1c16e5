"""Observation helpers keep evogym's arithmetic to the bit."""

import numpy as np

from tasks.observations import com_voxel_units, com_voxel_units_per_robot


def test_batched_com_in_voxel_units_is_evogyms_mean_to_the_bit():
    """The sight windows' edges fall on this COM: grouping robots by point count must give the
    bits of evogym's per-robot np.mean, for any batch (counts repeated, unique, padded rows)."""
    rng = np.random.default_rng(7)
    for _ in range(100):
        B, N = int(rng.integers(1, 70)), int(rng.integers(4, 300))
        pos = rng.normal(size=(B, N, 2)) * rng.uniform(0.1, 50) + rng.uniform(-5, 50)
        n_points = rng.integers(1, N + 1, size=B)
        assert np.array_equal(com_voxel_units(pos, n_points),
                              com_voxel_units_per_robot(pos, n_points))
