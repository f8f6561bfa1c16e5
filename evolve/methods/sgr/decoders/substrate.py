"""The paper's body decoder ("substrate", the default): the CPPN queried on a fixed body substrate.

The body network is a 2-3-5 perceptron (evolve/methods/sgr/substrates.py, `body_substrate`: inputs 1x2 at
z=1, hidden 1x3 at z=2 tanh, outputs 1x5 at z=3 identity) whose weights are CPPN output 0 at every
link; it is evaluated on each cell's (x, y) and the cell takes the argmax of its 5 material outputs.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cache
from typing import Any

import numpy as np

from evolve.methods.sgr.decoders.base import BodyDecoder
from evolve.methods.sgr.hyperneat import Expression, dense_layers, substrate_queries
from evolve.methods.sgr.substrates import body_substrate, cell_coordinates
from evolve.nn.cppn import CompiledCPPN


@cache
def _body_queries():
    return substrate_queries(body_substrate())


class SubstrateDecoder(BodyDecoder):
    """The SGR paper's body substrate, bit for bit as sgr decoded bodies before decoders were a
    choice."""
    name = "substrate"

    def body(self, cppn: CompiledCPPN, shape: tuple[int, int], expression: Expression,
             settings: Mapping[str, Any]) -> np.ndarray:
        """Argmax of the 2-3-5 body network's outputs at each cell's (x, y)."""
        q, slices = _body_queries()
        W1, b1, W2, b2 = dense_layers(cppn(q, (0,))[:, 0], slices, expression)
        x = cell_coordinates(shape)
        out = np.tanh(x @ W1 + b1) @ W2 + b2
        return np.argmax(out, axis=1).reshape(shape).astype(np.int64)
