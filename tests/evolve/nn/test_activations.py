"""A NEAT activation gives the same bits for one value alone (the JSON controller's scalars) as for
that value inside an array (the batched networks of evolution)."""

import numpy as np
import pytest

from evolve.nn.activations import NEAT_ACTIVATIONS


@pytest.mark.parametrize("name", sorted(NEAT_ACTIVATIONS))
def test_a_scalar_and_an_array_give_the_same_bits(name):
    """Each value of an array, passed again alone as a numpy float64, gives the same bits. With
    `z ** 2` in gauss the scalar went through C pow(), one ulp off z * z for about 1 value in
    1500 (glibc), and two paper champions replayed from their JSON 1e-16 and 5e-14 off."""
    f = NEAT_ACTIVATIONS[name]
    z = np.random.default_rng(7).normal(0.0, 1.5, 20_000)
    arr = f(z.reshape(40, 50, 10))  # a batch's (B, Q, nodes) block
    alone = np.array([float(f(np.float64(v))) for v in z])
    assert np.array_equal(arr.ravel(), alone)
