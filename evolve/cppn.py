"""A neat-python feed-forward genome compiled once into a numpy function over many queries.

HyperNEAT asks a CPPN for thousands of connection weights per genome; calling neat-python's
`activate` per query is the slow path this replaces. Node semantics are neat-python's:
value = activation(bias + response * aggregation(w_i * v_i)), with its activation scalings.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from neat.graphs import feed_forward_layers


def _sigmoid(z):
    return 1.0 / (1.0 + np.exp(-np.clip(5.0 * z, -60.0, 60.0)))


ACTIVATIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "sigmoid": _sigmoid,
    "tanh": lambda z: np.tanh(np.clip(2.5 * z, -60.0, 60.0)),
    "sin": lambda z: np.sin(np.clip(5.0 * z, -60.0, 60.0)),
    "gauss": lambda z: np.exp(-5.0 * np.clip(z, -3.4, 3.4) ** 2),
    "relu": lambda z: np.maximum(z, 0.0),
    "identity": lambda z: z,
    "clamped": lambda z: np.clip(z, -1.0, 1.0),
    "abs": np.abs,
    "square": np.square,
    "hat": lambda z: np.maximum(0.0, 1.0 - np.abs(z)),
}

AGGREGATIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "sum": lambda x: x.sum(axis=0),
    "product": lambda x: x.prod(axis=0),
    "max": lambda x: x.max(axis=0),
    "min": lambda x: x.min(axis=0),
    "mean": lambda x: x.mean(axis=0),
}


class CompiledCPPN:
    """`cppn(inputs)` with inputs (Q, n_inputs) returns (Q, n_outputs); outputs that no enabled
    path reaches read 0, as in neat-python's FeedForwardNetwork."""

    def __init__(self, genome, genome_config):
        self.input_keys = list(genome_config.input_keys)
        self.output_keys = list(genome_config.output_keys)
        conns = [c.key for c in genome.connections.values() if c.enabled]
        layers, required = feed_forward_layers(self.input_keys, self.output_keys, conns)
        known = required | set(self.input_keys)
        incoming: dict[int, list] = {}
        for i, o in conns:
            if i in known:
                incoming.setdefault(o, []).append((i, genome.connections[(i, o)].weight))
        self.steps = []
        for layer in layers:
            for node in sorted(layer):
                links = incoming.get(node, [])
                ng = genome.nodes[node]
                if ng.activation not in ACTIVATIONS:
                    raise ValueError(f"activation {ng.activation!r} is not supported by the "
                                     f"vectorized CPPN; use one of {sorted(ACTIVATIONS)}")
                if ng.aggregation not in AGGREGATIONS:
                    raise ValueError(f"aggregation {ng.aggregation!r} is not supported; use one of "
                                     f"{sorted(AGGREGATIONS)}")
                srcs = [i for i, _ in links]
                w = np.array([w for _, w in links], dtype=np.float64)
                self.steps.append((node, srcs, w, ng.bias, ng.response,
                                   ACTIVATIONS[ng.activation], AGGREGATIONS[ng.aggregation]))

    def __call__(self, inputs: np.ndarray) -> np.ndarray:
        x = np.asarray(inputs, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != len(self.input_keys):
            raise ValueError(f"CPPN expects (Q, {len(self.input_keys)}) inputs, got {x.shape}")
        values = {k: x[:, j] for j, k in enumerate(self.input_keys)}
        zero = np.zeros(len(x))
        for node, srcs, w, bias, response, act, agg in self.steps:
            if srcs:
                s = agg(np.stack([values[i] for i in srcs]) * w[:, None])
            else:  # a node with no enabled inputs: neat-python's empty sum (product: 1)
                s = zero + (1.0 if agg is AGGREGATIONS["product"] else 0.0)
            values[node] = act(bias + response * s)
        return np.stack([values.get(k, zero) for k in self.output_keys], axis=1)
