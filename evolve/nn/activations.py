"""Activation tables and the action map, named apart because the same name means two functions.

neat-python scales its activations (its "tanh" is tanh(2.5 z), its "sigmoid" 1 / (1 + e^(-5 z))),
and every network compiled from a neat-python genome must use those: `NEAT_ACTIVATIONS`. The SGR
controller's substrate layers use the plain functions (tanh(z)): `PLAIN_ACTIVATIONS`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

Fn = Callable[[np.ndarray], np.ndarray]


def _neat_sigmoid(z):
    return 1.0 / (1.0 + np.exp(-np.clip(5.0 * z, -60.0, 60.0)))


NEAT_ACTIVATIONS: dict[str, Fn] = {
    "sigmoid": _neat_sigmoid,
    "tanh": lambda z: np.tanh(np.clip(2.5 * z, -60.0, 60.0)),
    "sin": lambda z: np.sin(np.clip(5.0 * z, -60.0, 60.0)),
    # np.square, not ** 2: a numpy scalar's ** is C pow(), at times one ulp off z * z, so the JSON
    # controller's scalars and the batch's arrays (** 2 is square there) disagreed in last bits
    "gauss": lambda z: np.exp(-5.0 * np.square(np.clip(z, -3.4, 3.4))),
    "relu": lambda z: np.maximum(z, 0.0),
    "identity": lambda z: z,
    "clamped": lambda z: np.clip(z, -1.0, 1.0),
    "abs": np.abs,
    "square": np.square,
    "hat": lambda z: np.maximum(0.0, 1.0 - np.abs(z)),
}

NEAT_AGGREGATIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "sum": lambda x: x.sum(axis=0),
    "product": lambda x: x.prod(axis=0),
    "max": lambda x: x.max(axis=0),
    "min": lambda x: x.min(axis=0),
    "mean": lambda x: x.mean(axis=0),
}

PLAIN_ACTIVATIONS: dict[str, Fn] = {
    "tanh": np.tanh,
    "identity": lambda z: z,
    "relu": lambda z: np.maximum(z, 0.0),
    "sigmoid": lambda z: 1.0 / (1.0 + np.exp(-z)),
}

# a network output y in (-1, 1) drives an actuator at 1.1 + 0.5 y, evogym's range (0.6, 1.6)
ACTION_CENTRE, ACTION_HALF_RANGE = 1.1, 0.5


def to_action(y: np.ndarray) -> np.ndarray:
    """Network output y -> actuator target 1.1 + 0.5 y: (-1, 1) maps onto evogym's (0.6, 1.6); not
    clipped here (the simulator clips)."""
    return ACTION_CENTRE + ACTION_HALF_RANGE * y
