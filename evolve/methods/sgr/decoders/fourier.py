"""A richer body substrate ("fourier"): the paper's body network with Fourier features of (x, y) as
inputs and more hidden nodes, still queried HyperNEAT-style from the CPPN.

The cell's (x, y) (relative to the grid's centre, in [-1, 1]) becomes 2 + 4F inputs: x, y and, for
f = 1 .. F (setting `frequencies`, default 2), sin(f pi x), cos(f pi x), sin(f pi y), cos(f pi y).
They sit on a 1 x (2 + 4F) row at z=1, the hidden layer is a 1 x `hidden` row at z=2 (tanh;
default 6, the paper has 3) and the outputs 1x5 at z=3 (identity); every link's weight and every
node's bias is CPPN output 0 through the weight expression, as for the paper's substrate, and the
cell takes the argmax of its 5 material outputs. Periodic inputs let one smooth CPPN draw stripes
and checkers that a 2-3-5 perceptron of (x, y) cannot.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cache
from typing import Any

import numpy as np

from evolve.methods.sgr.decoders.base import BodyDecoder
from evolve.methods.sgr.hyperneat import Expression, dense_layers, substrate_queries
from evolve.methods.sgr.substrates import N_TYPES, Substrate, cell_coordinates, grid_layer


@cache
def fourier_substrate(frequencies: int, hidden: int) -> Substrate:
    """Inputs 1 x (2 + 4F) at z=1, hidden 1 x `hidden` at z=2 (tanh), outputs 1x5 at z=3."""
    return Substrate((grid_layer(1, 2 + 4 * frequencies, 1.0), grid_layer(1, hidden, 2.0),
                      grid_layer(1, N_TYPES, 3.0)), ("tanh", "identity"))


@cache
def _queries(frequencies: int, hidden: int):
    return substrate_queries(fourier_substrate(frequencies, hidden))


def features(shape: tuple[int, int], frequencies: int) -> np.ndarray:
    """(H*W, 2 + 4F) inputs of every cell: x, y, then per f: sin, cos of f pi x, sin, cos of f pi y."""
    xy = cell_coordinates(shape)
    cols = [xy[:, 0], xy[:, 1]]
    for f in range(1, frequencies + 1):
        for v in (xy[:, 0], xy[:, 1]):
            cols += [np.sin(f * np.pi * v), np.cos(f * np.pi * v)]
    return np.stack(cols, axis=1)


class FourierDecoder(BodyDecoder):
    """Argmax of a (2 + 4F)-hidden-5 body network of each cell's Fourier features."""
    name = "fourier"
    settings = {"frequencies": ((int,), 2, 1, 64), "hidden": ((int,), 6, 1, 1024)}

    def body(self, cppn, shape: tuple[int, int], expression: Expression,
             settings: Mapping[str, Any]) -> np.ndarray:
        """The body network (module docstring) on every cell."""
        q, slices = _queries(settings["frequencies"], settings["hidden"])
        W1, b1, W2, b2 = dense_layers(cppn(q, (0,))[:, 0], slices, expression)
        out = np.tanh(features(shape, settings["frequencies"]) @ W1 + b1) @ W2 + b2
        return np.argmax(out, axis=1).reshape(shape).astype(np.int64)
