"""A NEAT network controller in plain JSON (the baselines' champions), runnable with numpy only.

Nodes are listed in evaluation order with their incoming links; value = activation(bias +
response * sum(w * value(src))) with neat-python's activation scalings (`NEAT_ACTIVATIONS`).

Where the network is the genome the champion file records anyway (direct NEAT), the file may hold
it as that genome's compiled form instead (DERIVED_FORMAT, `to_derived_json`): the pin counts,
offsets and action cells, and a SHA-256 of the nodes, which reading compiles again and checks. At
10x10 that is ~1 KB instead of ~80 KB.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass

import numpy as np

from evolve.nn.activations import NEAT_ACTIVATIONS, to_action
from evolve.nn.feedforward import compile_genome
from evolve.nn.genome_record import GenomeKeys, genome_from_record

FORMAT = "sgr-graph-controller-1"
DERIVED_FORMAT = "sgr-genome-graph-controller-1"


def nodes_digest(nodes: list[dict]) -> str:
    """SHA-256 of the nodes as compact JSON (`json.dumps(nodes, separators=(",", ":"))`)."""
    return hashlib.sha256(json.dumps(nodes, separators=(",", ":")).encode()).hexdigest()


@dataclass
class GraphController:
    """A NEAT network as plain data (the baselines' champions): the one-robot, numpy-only
    counterpart of `GraphPolicy`, with the same offsets and layouts."""
    input_keys: list[int]
    output_keys: list[int]
    nodes: list[dict]  # {"key", "bias", "response", "activation", "links": [[src, weight], ...]}
    input_size: int  # observation length
    input_offset: int  # observation enters inputs [offset, offset + input_size)
    output_offset: int  # action of actuator i = output[output_offset + action_cells[i]]
    action_cells: np.ndarray
    # "per_cell" layout: actuator i is its own query, its cell's (x, y) in inputs 0-1, and its
    # action is output[output_offset]
    cell_inputs: np.ndarray | None = None

    def __repr__(self) -> str:
        links = sum(len(n.get("links", ())) for n in self.nodes)
        return (f"GraphController({len(self.input_keys)} inputs, {len(self.output_keys)} outputs, "
                f"{len(self.nodes)} nodes, {links} connections, {len(self.action_cells)} actuators)")

    def __post_init__(self) -> None:
        # each node's links sorted by their source's slot in `NetworkBatch` (inputs, then nodes in
        # evaluation order: by depth, then key), the order its inputs are summed in; sorted once
        keys = [*self.input_keys, *(n["key"] for n in self.nodes)]
        slot = {k: j for j, k in enumerate(keys)}
        self._links = [sorted(n["links"], key=lambda link: slot[link[0]]) for n in self.nodes]

    @classmethod
    def from_genome(cls, genome, genome_config, input_size: int, input_offset: int,
                    output_offset: int, action_cells: np.ndarray,
                    cell_inputs: np.ndarray | None = None) -> GraphController:
        """Compile a genome (`compile_genome`) into this plain form; offsets and action cells as in
        `GraphPolicy` (direct: 2 and 5, nested: 0 and 0)."""
        net = compile_genome(genome, genome_config)
        inputs, outputs = list(net.input_keys), list(net.output_keys)
        nodes = [{"key": n.key, "bias": n.bias, "response": n.response, "activation": n.activation,
                  "links": [[i, w] for i, w in n.links]} for n in net.nodes]
        return cls(inputs, outputs, nodes, input_size, input_offset, output_offset,
                   np.asarray(action_cells, dtype=np.int64),
                   None if cell_inputs is None else np.asarray(cell_inputs, dtype=np.float64))

    def outputs(self, obs: np.ndarray, xy: np.ndarray | None = None) -> np.ndarray:
        """Every output for one observation (cut to `input_size`); `xy` fills inputs 0-1 (per_cell
        layout); outputs no path reaches read 0."""
        x = np.zeros(len(self.input_keys))
        x[self.input_offset:self.input_offset + self.input_size] = obs[:self.input_size]
        if xy is not None:
            x[0:2] = xy
        v = dict(zip(self.input_keys, x, strict=True))
        for n, links in zip(self.nodes, self._links, strict=True):
            s = 0.0
            for i, w in links:
                s += v[i] * w  # one by one in slot order: `NetworkBatch`'s arithmetic to the bit
            v[n["key"]] = float(NEAT_ACTIVATIONS[n["activation"]](np.float64(n["bias"] + n["response"] * s)))
        return np.array([v.get(k, 0.0) for k in self.output_keys])

    def act(self, obs: np.ndarray) -> np.ndarray:
        """(n_actuators,) actions 1.1 + 0.5 y in evogym's actuator order; with `cell_inputs` one
        query per actuator."""
        if self.cell_inputs is None:
            y = self.outputs(obs)[self.output_offset + self.action_cells]
        else:
            y = np.array([self.outputs(obs, xy)[self.output_offset] for xy in self.cell_inputs])
        return to_action(y)

    def to_json(self) -> dict:
        """Self-contained JSON (format sgr-graph-controller-1, with a `doc` of the semantics),
        runnable with numpy alone."""
        return {"format": FORMAT, "input_keys": self.input_keys, "output_keys": self.output_keys,
                "nodes": self.nodes, "input_size": self.input_size, "input_offset": self.input_offset,
                "output_offset": self.output_offset, "action_cells": self.action_cells.tolist(),
                "cell_inputs": None if self.cell_inputs is None else self.cell_inputs.tolist(),
                "doc": "inputs: zeros with the observation at [input_offset, +input_size); nodes in "
                       "order: value = activation(bias + response * s), s = 0 plus value[src] * w added one "
                       "link at a time, sources ordered inputs first (by index) then nodes (by list "
                       "position), neat-python activations; action = 1.1 + 0.5 * "
                       "output[output_offset + action_cells]; when "
                       "cell_inputs is given, actuator i is a query of its own with cell_inputs[i] "
                       "in inputs 0-1 and action 1.1 + 0.5 * output[output_offset]"}

    def to_derived_json(self) -> dict:
        """The controller as the compiled form of the champion file's genome (DERIVED_FORMAT): what
        `to_json` holds but the nodes, which `from_derived_json` compiles again from the genome and
        checks against `sha256`. neat-python's pins: inputs -1..-num_inputs, outputs 0..num_outputs-1."""
        return {"format": DERIVED_FORMAT, "num_inputs": len(self.input_keys),
                "num_outputs": len(self.output_keys), "input_size": self.input_size,
                "input_offset": self.input_offset, "output_offset": self.output_offset,
                "action_cells": self.action_cells.tolist(),
                "cell_inputs": None if self.cell_inputs is None else self.cell_inputs.tolist(),
                "sha256": nodes_digest(self.nodes),
                "doc": f"The {FORMAT} network whose nodes are this file's 'genome' compiled (enabled links "
                       "on a path from the inputs to an output, nodes by depth then key; "
                       "evolve/nn/feedforward.py); sha256 is that of the nodes as compact JSON. "
                       "evolve.load_champion compiles it again and checks the digest."}

    @classmethod
    def from_derived_json(cls, d: dict, genome: dict) -> GraphController:
        """Inverse of `to_derived_json`, with the champion file's genome record; ValueError when the
        genome no longer compiles to the recorded nodes."""
        keys = GenomeKeys(int(d["num_inputs"]), int(d["num_outputs"]))
        cells = d.get("cell_inputs")
        ctrl = cls.from_genome(genome_from_record(genome, keys), keys, int(d["input_size"]),
                               int(d["input_offset"]), int(d["output_offset"]),
                               np.asarray(d["action_cells"], dtype=np.int64),
                               None if cells is None else np.asarray(cells, dtype=np.float64))
        if nodes_digest(ctrl.nodes) != d["sha256"]:
            raise ValueError("compiling the genome no longer gives the recorded nodes (sha256 differs)")
        return ctrl

    @classmethod
    def from_json(cls, d: dict) -> GraphController:
        """Inverse of `to_json`; a file without `cell_inputs` loads as the one-query layout."""
        cells = d.get("cell_inputs")
        return cls(list(d["input_keys"]), list(d["output_keys"]), list(d["nodes"]), int(d["input_size"]),
                   int(d["input_offset"]), int(d["output_offset"]), np.asarray(d["action_cells"]),
                   None if cells is None else np.asarray(cells, dtype=np.float64))


def graph_of_record(record: dict) -> GraphController:
    """A champion record's controller recorded in full (FORMAT): the reader direct and nested
    register (evolve/methods/formats.py)."""
    return GraphController.from_json(record["controller"])
