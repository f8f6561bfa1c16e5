"""One compile of a neat-python genome into a feed-forward graph, shared by every network we run
(the CPPN, the batched NEAT networks, the JSON graph controller), so they cannot disagree on which
nodes and links count.

Semantics are neat-python's FeedForwardNetwork: only enabled links; nodes in its feed-forward
layers (those on a path from the inputs to an output); links from nodes off those paths ignored;
value = activation(bias + response * aggregation(w_i * v_i)); outputs no path reaches read 0.
The layering is neat-python 2.0's `neat.graphs.feed_forward_layers` (the same layers, node for
node, for any genome), computed here in time linear in nodes + links: neat-python's rescans every
link for every node of every layer, which took minutes on a genome of 100,000 nodes.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass


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


def required_for_output(inputs: Iterable[int], outputs: Iterable[int],
                        connections: Iterable[tuple[int, int]]) -> set[int]:
    """The nodes an output's value needs, as neat-python 2.0's `required_for_output` finds them:
    a search backwards from the outputs, level by level, that stops at the first level holding
    inputs only; inputs are never in the set. Linear in nodes + links.

    Args:
        inputs: the input pins' keys.
        outputs: the output nodes' keys (disjoint from `inputs`).
        connections: the enabled links (source, destination).
    Returns:
        The outputs and every non-input node the search reached.
    """
    inputs = set(inputs)
    preds: dict[int, list[int]] = {}
    for a, b in dict.fromkeys(connections):
        preds.setdefault(b, []).append(a)
    required, seen = set(outputs), set(outputs)
    frontier = list(seen)
    while True:  # neat-python's rounds: each round's new sources are the sources of the last round's
        found = {a for b in frontier for a in preds.get(b, ()) if a not in seen}
        if not found or found <= inputs:
            return required
        required |= found - inputs
        seen |= found
        frontier = list(found)


def feed_forward_layers(inputs: Iterable[int], outputs: Iterable[int],
                        connections: Iterable[tuple[int, int]]) -> tuple[list[set[int]], set[int]]:
    """neat-python 2.0's `feed_forward_layers`, the same layers for any links, in time linear in
    nodes + links (Kahn's algorithm by rounds). The required nodes without incoming links come
    first, as one layer; then each layer is every required node not yet placed that has a link
    from an input or a placed node and whose required sources are all placed. Nodes on a cycle,
    and nodes behind them, are never placed.

    Args:
        inputs: the input pins' keys.
        outputs: the output nodes' keys (disjoint from `inputs`).
        connections: the enabled links (source, destination).
    Returns:
        The layers (sets of node keys) and the required nodes (`required_for_output`).
    """
    inputs, links = list(inputs), list(dict.fromkeys(connections))
    required = required_for_output(inputs, outputs, links)
    succs: dict[int, list[int]] = {}
    waiting: dict[int, int] = {}  # a required node with links in: its required sources not yet placed
    for a, b in links:
        succs.setdefault(a, []).append(b)
        if b in required:
            waiting[b] = waiting.get(b, 0) + (a in required)
    bias = required - waiting.keys()  # required, no incoming link: value activation(bias)
    layers = [set(bias)] if bias else []
    reached: set[int] = set()  # has a link from an input or a placed node
    frontier = list(dict.fromkeys([*inputs, *bias]))
    while True:
        touched = []
        for a in frontier:
            counts = a in required
            for b in succs.get(a, ()):
                if b in waiting:
                    reached.add(b)
                    waiting[b] -= counts
                    touched.append(b)
        layer = {b for b in touched if b in waiting and waiting[b] == 0}
        if not layer:
            return layers, required
        for b in layer:
            del waiting[b]
        layers.append(layer)
        frontier = list(layer)


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
