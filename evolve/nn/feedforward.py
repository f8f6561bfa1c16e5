"""One compile of a neat-python genome into a feed-forward graph, shared by every network we run
(the CPPN, the batched NEAT networks, the JSON graph controller), so they cannot disagree on which
nodes and links count.

Semantics are neat-python's FeedForwardNetwork: only enabled links; nodes in its feed-forward
layers (those on a path from the inputs to an output); links from nodes off those paths ignored;
value = activation(bias + response * aggregation(w_i * v_i)); outputs no path reaches read 0.
"""

from __future__ import annotations

from dataclasses import dataclass

from neat.graphs import feed_forward_layers


@dataclass(frozen=True)
class Node:
    """One compiled node: value = activation(bias + response * aggregation(w * value(src))) over
    `links`."""
    key: int
    bias: float
    response: float
    activation: str
    aggregation: str
    links: tuple[tuple[int, float], ...]  # (source key, weight), in the genome's link order


@dataclass(frozen=True)
class FeedForward:
    """A genome reduced to what evaluation uses: input and output keys and the nodes of
    neat-python's feed-forward layers, by depth."""
    input_keys: tuple[int, ...]
    output_keys: tuple[int, ...]
    layers: tuple[tuple[Node, ...], ...]  # by depth, nodes sorted by key within a layer

    @property
    def nodes(self) -> list[Node]:
        """Every node in an evaluation order."""
        return [n for layer in self.layers for n in layer]


def compile_genome(genome, genome_config) -> FeedForward:
    """Compile with neat-python's FeedForwardNetwork semantics (module docstring): enabled links
    only, only the nodes of its feed-forward layers, grouped by depth."""
    inputs, outputs = tuple(genome_config.input_keys), tuple(genome_config.output_keys)
    conns = [c.key for c in genome.connections.values() if c.enabled]
    layers, required = feed_forward_layers(list(inputs), list(outputs), conns)
    known = required | set(inputs)
    incoming: dict[int, list[tuple[int, float]]] = {}
    for i, o in conns:
        if i in known:
            incoming.setdefault(o, []).append((i, genome.connections[(i, o)].weight))
    compiled = []
    for layer in layers:
        nodes = []
        for k in sorted(layer):
            ng = genome.nodes[k]
            nodes.append(Node(k, ng.bias, ng.response, ng.activation, ng.aggregation,
                              tuple(incoming.get(k, ()))))
        compiled.append(tuple(nodes))
    return FeedForward(inputs, outputs, tuple(compiled))
