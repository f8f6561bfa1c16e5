"""HyperNEAT substrates of the SGR paper: node coordinates of the body and controller networks.

Layers are grids spread over [-1, 1] (a single row or column sits at 0); row 0 of a grid is at
y = +1 so grid cells line up with the body matrix (row 0 = top). The body network lives at z > 0,
the controller network at z < 0, so one CPPN query pass yields both with no links between them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np

N_TYPES = 5  # empty, rigid, soft, H actuator, V actuator


def spread(n: int) -> np.ndarray:
    """n coordinates evenly over [-1, 1]; a single node sits at 0 (linspace would put it at -1)."""
    return np.zeros(1) if n == 1 else np.linspace(-1.0, 1.0, n)


def grid_layer(rows: int, cols: int, z: float) -> np.ndarray:
    """(rows*cols, 3) coordinates in row-major order."""
    ys = -spread(rows)  # row 0 at the top (y = +1)
    xs = spread(cols)
    yy, xx = np.meshgrid(ys, xs, indexing="ij")
    return np.stack([xx.ravel(), yy.ravel(), np.full(rows * cols, float(z))], axis=1)


@dataclass(frozen=True)
class Substrate:
    """A layered feed-forward substrate: layers[0] inputs, layers[-1] outputs."""

    layers: tuple[np.ndarray, ...]
    activations: tuple[str, ...]  # one per non-input layer


def cell_coordinates(shape: tuple[int, int]) -> np.ndarray:
    """(H*W, 2) (x, y) of every body cell relative to the grid centre, scaled to [-1, 1]."""
    return grid_layer(shape[0], shape[1], 0.0)[:, :2]


@cache
def body_substrate() -> Substrate:
    """Paper table "morphology substrate": in 1x2 (z=1), hidden 1x3 (z=2), out 1x5 (z=3)."""
    return Substrate((grid_layer(1, 2, 1.0), grid_layer(1, 3, 2.0), grid_layer(1, N_TYPES, 3.0)),
                     ("tanh", "identity"))


def controller_side(obs_len: int) -> int:
    """k of the k x k input grid holding an observation of obs_len values."""
    return max(1, math.ceil(math.sqrt(obs_len)))


@cache
def controller_substrate(k: int, shape: tuple[int, int] = (5, 5)) -> Substrate:
    """Paper table "controller substrate": in k x k (z=-1), hidden 5x5 (z=-2), out 5x5 (z=-3,
    one per voxel)."""
    return Substrate((grid_layer(k, k, -1.0), grid_layer(*shape, -2.0), grid_layer(*shape, -3.0)),
                     ("tanh", "tanh"))
