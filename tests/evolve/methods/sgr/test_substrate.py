"""Substrate geometry of the SGR paper and the HyperNEAT weight expression."""

import numpy as np
import pytest

from evolve.methods.sgr.hyperneat import Expression, substrate_queries
from evolve.methods.sgr.substrates import (
    body_substrate,
    cell_coordinates,
    controller_side,
    controller_substrate,
    grid_layer,
)


def test_body_substrate_layers_sit_at_positive_z_with_the_paper_sizes():
    s = body_substrate()
    assert [len(L) for L in s.layers] == [2, 3, 5]
    assert [set(L[:, 2]) for L in s.layers] == [{1.0}, {2.0}, {3.0}]
    assert np.array_equal(s.layers[0][:, 0], [-1.0, 1.0]) and np.all(s.layers[2][:, 1] == 0.0)
    assert np.allclose(s.layers[2][:, 0], [-1, -0.5, 0, 0.5, 1])
    assert s.activations == ("tanh", "identity")


@pytest.mark.parametrize("obs_len, k", [(1, 1), (4, 2), (5, 3), (74, 9), (81, 9), (82, 10)])
def test_controller_input_grid_is_the_smallest_square_holding_the_observation(obs_len, k):
    assert controller_side(obs_len) == k
    s = controller_substrate(k)
    assert [len(L) for L in s.layers] == [k * k, 25, 25]
    assert [set(L[:, 2]) for L in s.layers] == [{-1.0}, {-2.0}, {-3.0}]


def test_grid_rows_run_top_down_like_the_body_matrix_and_span_minus_one_to_one():
    g = grid_layer(5, 5, 0.0)
    assert np.array_equal(g[0, :2], [-1.0, 1.0])  # row 0, col 0: top left
    assert np.array_equal(g[24, :2], [1.0, -1.0])  # bottom right
    assert np.array_equal(cell_coordinates((5, 5))[12], [0.0, 0.0])  # centre cell


def test_body_and_controller_queries_never_cross_z_zero():
    for sub, sign in ((body_substrate(), 1), (controller_substrate(9), -1)):
        q, slices = substrate_queries(sub)
        assert len(q) == sum(b - a for a, b, _ in slices)
        assert np.all(q[:, 5] * sign > 0)  # every target node on its own side
        assert np.all((q[:, 2] * sign > 0) | np.all(q[:, 0:3] == 0.0, axis=1))  # sources, or the bias origin
        assert np.all(q[:, 6] == 1.0)


def test_weight_expression_cuts_small_weights_and_rescales_the_rest():
    e = Expression(threshold=0.2, max_weight=1.0)
    w = np.array([0.0, 0.2, -0.2, 0.21, 0.6, -0.6, 1.0, -1.0])
    assert np.allclose(e(w), [0, 0, 0, 0.0125, 0.5, -0.5, 1.0, -1.0])
    assert np.allclose(Expression(0.2, 3.0)(np.array([0.6])), [1.5])
