"""The direct CPPN query ("cppn", Cheney et al. 2013, "Unshackling evolution"): the genome's CPPN read
at each cell, with a presence output apart from the material outputs.

Each cell asks the CPPN once, with inputs (x1, y1, z1, x2, y2, z2, bias) = (x, y, d, 0, 0, Z_BODY, 1):
the cell's x and y relative to the grid's centre, scaled to [-1, 1] (row 0 = top = y +1, as the
substrates have it), d its distance to the centre over sqrt(2) (in [0, 1]), and z2 = +1. Every query
of the controller substrate has z2 <= -2 (and z1 <= 0), so the body's reading and the controller's
are apart in the CPPN's input space, as SGR's two substrates are (z > 0 and z < 0); x2 = y2 = 0 is
the one point the queries share. The genome's CPPN has 5 body outputs: output 0 is presence (the
cell is filled when it is > 0), outputs 1-4 rate rigid, soft, H and V actuator, and a filled cell
takes the material of the largest. With `cppn_outputs: 2` the controller reads its own output
column (5), else the presence column (0), queried at its own substrate. No settings.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from evolve.methods.sgr.decoders.base import BodyDecoder
from evolve.methods.sgr.hyperneat import Expression
from evolve.methods.sgr.substrates import cell_coordinates
from evolve.nn.cppn import CompiledCPPN

Z_BODY = 1.0  # z2 of every body query: the body's side of the CPPN (the controller's is z2 <= -2)


def cell_queries(shape: tuple[int, int]) -> np.ndarray:
    """(H*W, 7) CPPN inputs (x, y, d, 0, 0, Z_BODY, 1) of every cell, row-major."""
    xy = cell_coordinates(shape)
    q = np.zeros((len(xy), 7))
    q[:, 0:2] = xy
    q[:, 2] = np.sqrt((xy ** 2).sum(axis=1)) / np.sqrt(2.0)
    q[:, 5] = Z_BODY
    q[:, 6] = 1.0
    return q


class CppnQueryDecoder(BodyDecoder):
    """Presence output > 0 -> filled, with the material of the largest of outputs 1-4."""
    name = "cppn"
    body_outputs = 5

    def body(self, cppn: CompiledCPPN, shape: tuple[int, int], expression: Expression,
             settings: Mapping[str, Any]) -> np.ndarray:
        """The CPPN at each cell (module docstring); the weight expression plays no part."""
        out = cppn(cell_queries(shape), tuple(range(self.body_outputs)))
        material = 1 + np.argmax(out[:, 1:5], axis=1)
        return np.where(out[:, 0] > 0.0, material, 0).reshape(shape).astype(np.int64)
