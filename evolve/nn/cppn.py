"""A neat-python feed-forward genome compiled once into a numpy function over many queries.

HyperNEAT asks a CPPN for thousands of connection weights per genome; calling neat-python's
`activate` per query is the slow path this replaces. Node semantics are neat-python's:
value = activation(bias + response * aggregation(w_i * v_i)), with its activation scalings.
"""

from __future__ import annotations

import numpy as np

from evolve.nn.activations import NEAT_ACTIVATIONS, NEAT_AGGREGATIONS
from evolve.nn.feedforward import compile_genome
from tsim.errors import SgrError


class CompiledCPPN:
    """`cppn(inputs)` with inputs (Q, n_inputs) returns (Q, n_outputs); outputs that no enabled
    path reaches read 0, as in neat-python's FeedForwardNetwork."""

    def __init__(self, genome, genome_config):
        net = compile_genome(genome, genome_config)
        self.input_keys, self.output_keys = list(net.input_keys), list(net.output_keys)
        self.steps = []
        for n in net.nodes:
            if n.activation not in NEAT_ACTIVATIONS:
                raise SgrError(f"activation {n.activation!r} is not supported by the "
                               f"vectorized CPPN; use one of {sorted(NEAT_ACTIVATIONS)}")
            if n.aggregation not in NEAT_AGGREGATIONS:
                raise SgrError(f"aggregation {n.aggregation!r} is not supported; use one of "
                               f"{sorted(NEAT_AGGREGATIONS)}")
            srcs = [i for i, _ in n.links]
            w = np.array([w for _, w in n.links], dtype=np.float64)
            self.steps.append((n.key, srcs, w, n.bias, n.response, NEAT_ACTIVATIONS[n.activation],
                               NEAT_AGGREGATIONS[n.aggregation]))
        self._needed: dict[tuple[int, ...], set[int]] = {}

    def needed(self, columns: tuple[int, ...]) -> set[int]:
        """The nodes that output `columns` depend on (the outputs' keys and their ancestors)."""
        if columns not in self._needed:
            srcs = {step[0]: step[1] for step in self.steps}
            todo = [self.output_keys[c] for c in columns]
            seen: set[int] = set()
            while todo:
                k = todo.pop()
                if k not in seen:
                    seen.add(k)
                    todo += srcs.get(k, [])
            self._needed[columns] = seen
        return self._needed[columns]

    def __call__(self, inputs: np.ndarray, columns: tuple[int, ...] | None = None) -> np.ndarray:
        """(Q, n_outputs) outputs, or with `columns` those outputs alone, (Q, len(columns)): only
        the nodes they depend on are computed, each as in the full pass (the same numbers, bit for
        bit: a node's value is a function of its ancestors' alone)."""
        x = np.asarray(inputs, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != len(self.input_keys):
            raise ValueError(f"CPPN expects (Q, {len(self.input_keys)}) inputs, got {x.shape}")
        values = {k: x[:, j] for j, k in enumerate(self.input_keys)}
        zero = np.zeros(len(x))
        needed = None if columns is None else self.needed(tuple(columns))
        outputs = self.output_keys if columns is None else [self.output_keys[c] for c in columns]
        for node, srcs, w, bias, response, act, agg in self.steps:
            if needed is not None and node not in needed:
                continue
            if srcs:
                s = agg(np.stack([values[i] for i in srcs]) * w[:, None])
            else:  # a node with no enabled inputs: neat-python's empty sum (product: 1)
                s = zero + (1.0 if agg is NEAT_AGGREGATIONS["product"] else 0.0)
            values[node] = act(bias + response * s)
        return np.stack([values.get(k, zero) for k in outputs], axis=1)
