"""A growth decoder ("growth", neural-cellular-automaton style, as in Horibe et al. 2021): one
cell-local rule applied K times from a seed cell.

Every cell holds a state of C = 8 numbers (0: presence, 1-4: the materials' ratings, 5-7: free).
At the start the seed cell, the centre ((H-1)//2, (W-1)//2), is filled with state (1, 0, ..., 0)
and every other cell is empty with state 0. A step computes, for every cell at once, a new state
new = tanh(W2 tanh(W1 v + b1) + b2) of v, the states of the cell and of its 4 neighbours (above,
below, left, right; 0 beyond the grid), 5C numbers. A cell becomes filled when one of its 4
neighbours is filled and its new presence is > 0; a filled cell stays filled, and an empty cell's
state is 0 again. So the body grows from the seed and is always connected. After K steps (setting
`steps`; null, the default: max(H, W), enough to reach every cell from the centre) a filled cell
takes the material of the largest of its state's numbers 1-4.

The rule's weights are read from the CPPN HyperNEAT-style (output 0, through the weight
expression) on a substrate of its own at 0 < z < 1, between the controller's (z < 0) and the
paper's body substrate (z 1-3), so that its queries are apart from both yet of the size of theirs
(at z of 4 and more, a CPPN whose output node is a Gaussian reads ~0 everywhere: no rule): input
node (neighbour at offset (dx, dy), channel c) at (dx, dy, 0.25 + 0.25 c/C) (above: dy = +1,
right: dx = +1), hidden 1 x C at z=0.6 (tanh), outputs 1 x C at z=0.8 (tanh); biases are queries
from the origin, as everywhere. Pure numpy, deterministic.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cache
from typing import Any

import numpy as np

from evolve.methods.sgr.decoders.base import BodyDecoder
from evolve.methods.sgr.hyperneat import Expression, dense_layers, substrate_queries
from evolve.methods.sgr.substrates import Substrate, grid_layer

CHANNELS = 8
Z_INPUT, Z_HIDDEN, Z_OUTPUT = 0.25, 0.6, 0.8  # the rule's layers (module docstring)
# the cell itself, then its neighbours above, below, left and right, as (dx, dy) (row 0 = top = +y)
NEIGHBOURS = ((0, 0), (0, 1), (0, -1), (-1, 0), (1, 0))


@cache
def rule_substrate() -> Substrate:
    """The rule's network: 5C inputs (neighbour-major, then channel), C hidden, C outputs."""
    inputs = np.array([(dx, dy, Z_INPUT + 0.25 * c / CHANNELS) for dx, dy in NEIGHBOURS
                       for c in range(CHANNELS)], dtype=np.float64)
    return Substrate((inputs, grid_layer(1, CHANNELS, Z_HIDDEN), grid_layer(1, CHANNELS, Z_OUTPUT)),
                     ("tanh", "tanh"))


@cache
def _queries():
    return substrate_queries(rule_substrate())


def _shifted(a: np.ndarray) -> list[np.ndarray]:
    """`a` (H, W, ...) as seen from each cell's neighbour above, below, left and right (0 beyond)."""
    up, down, left, right = (np.zeros_like(a) for _ in range(4))
    up[1:], down[:-1] = a[:-1], a[1:]
    left[:, 1:], right[:, :-1] = a[:, :-1], a[:, 1:]
    return [up, down, left, right]


def steps_of(settings: Mapping[str, Any], shape: tuple[int, int]) -> int:
    """K: the `steps` setting, or max(H, W) when it is null."""
    return settings["steps"] if settings["steps"] is not None else max(shape)


def grow(W1: np.ndarray, b1: np.ndarray, W2: np.ndarray, b2: np.ndarray, shape: tuple[int, int],
         steps: int) -> np.ndarray:
    """(H, W) material codes after `steps` steps of the rule (module docstring) from the seed."""
    H, W = shape
    state = np.zeros((H, W, CHANNELS))
    filled = np.zeros((H, W), dtype=bool)
    seed = ((H - 1) // 2, (W - 1) // 2)
    state[seed + (0,)] = 1.0
    filled[seed] = True
    for _ in range(steps):
        v = np.concatenate([state, *_shifted(state)], axis=2).reshape(H * W, 5 * CHANNELS)
        new = np.tanh(np.tanh(v @ W1 + b1) @ W2 + b2).reshape(H, W, CHANNELS)
        near = np.logical_or.reduce(_shifted(filled))
        filled = filled | (near & (new[:, :, 0] > 0.0))
        state = np.where(filled[:, :, None], new, 0.0)
    material = 1 + np.argmax(state[:, :, 1:5], axis=2)
    return np.where(filled, material, 0).astype(np.int64)


class GrowthDecoder(BodyDecoder):
    """K steps of a cell-local rule from the centre cell; a body that is always connected."""
    name = "growth"
    settings = {"steps": ((int, type(None)), None, 1, 10_000)}

    def body(self, cppn, shape: tuple[int, int], expression: Expression,
             settings: Mapping[str, Any]) -> np.ndarray:
        """The rule's weights from the CPPN, then `grow`."""
        q, slices = _queries()
        W1, b1, W2, b2 = dense_layers(cppn(q, (0,))[:, 0], slices, expression)
        return grow(W1, b1, W2, b2, tuple(shape), steps_of(settings, shape))
