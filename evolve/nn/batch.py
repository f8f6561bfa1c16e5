"""Many arbitrary-topology neat-python networks evaluated together.

Each genome is compiled to layers by depth (neat-python's feed-forward layering); layer d of every
genome is padded to the widest layer d in the batch, so one layer is one pass over the whole
batch: values[:, slots_d] = act(bias + response * (values @ W_d)), the products summed in slot
order (see `forward`). Slots: the inputs, then each depth's padded block, then one slot that stays
0 (outputs no enabled path reaches read it, as in neat-python).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evolve.nn.activations import NEAT_ACTIVATIONS, to_action
from evolve.nn.feedforward import compile_genome

ACT_NAMES = tuple(NEAT_ACTIVATIONS)


class NetworkBatch:
    """`forward(x)` with x (B, Q, n_inputs) -> (B, Q, n_outputs): network b applied to its Q rows."""

    def __init__(self, genomes: Sequence, genome_config):
        """`genome_config`: one for all genomes, or one per genome (input counts may differ, e.g.
        controllers of different bodies; the batch takes the largest, smaller ones read zeros)."""
        many = isinstance(genome_config, (list, tuple))
        configs = list(genome_config) if many else [genome_config] * len(genomes)
        self.n_in = max(len(c.input_keys) for c in configs)
        self.n_out = len(configs[0].output_keys)
        if any(len(c.output_keys) != self.n_out for c in configs):
            raise ValueError("all networks of a batch need the same number of outputs")
        compiled = [compile_genome(g, c) for g, c in zip(genomes, configs, strict=True)]
        for net in compiled:
            for n in net.nodes:
                if n.aggregation != "sum":
                    raise ValueError(f"aggregation {n.aggregation!r} is not supported by batched "
                                     "networks (sum only)")
        B = len(genomes)
        depth = max((len(net.layers) for net in compiled), default=0)
        widths = [max((len(net.layers[d]) if d < len(net.layers) else 0) for net in compiled)
                  for d in range(depth)]
        starts = np.concatenate([[self.n_in], self.n_in + np.cumsum(widths)]).astype(int)
        self.n_slots = int(starts[-1]) + 1
        zero_slot = self.n_slots - 1
        self.blocks = []  # per depth: (start, W (B, n_slots, w), bias, response, act index)
        for d, w in enumerate(widths):
            self.blocks.append((int(starts[d]), np.zeros((B, self.n_slots, w)), np.zeros((B, w)),
                                np.zeros((B, w)), np.zeros((B, w), dtype=np.int64)))
        self.out_slot = np.full((B, self.n_out), zero_slot, dtype=np.int64)
        act_index = {a: i for i, a in enumerate(ACT_NAMES)}
        for b, net in enumerate(compiled):
            slot = {k: j for j, k in enumerate(net.input_keys)}
            for d, layer in enumerate(net.layers):
                for j, node in enumerate(layer):
                    slot[node.key] = int(starts[d]) + j
            for d, layer in enumerate(net.layers):
                _, W, bias, resp, act = self.blocks[d]
                for j, node in enumerate(layer):
                    if node.activation not in act_index:
                        raise ValueError(f"activation {node.activation!r} is not supported; "
                                         f"use one of {sorted(act_index)}")
                    for i, w in node.links:
                        W[b, slot[i], j] += w
                    bias[b, j], resp[b, j], act[b, j] = node.bias, node.response, act_index[node.activation]
            for o, k in enumerate(net.output_keys):
                if k in slot:
                    self.out_slot[b, o] = slot[k]
        self._used = [sorted(set(np.unique(a).tolist())) for *_, a in self.blocks]
        # source slots with a weight in some network of the batch, per depth, in slot order
        self._sources = [np.nonzero(np.any(W != 0.0, axis=(0, 2)))[0].tolist() for _, W, *_ in self.blocks]
        self._cast: dict = {}  # dtype -> the blocks rounded to it

    def forward(self, x: np.ndarray) -> np.ndarray:
        """x (B, Q, n_in) -> (B, Q, n_out), network b on its Q rows; ValueError for another B or
        input width (pad narrower inputs with zeros first)."""
        B, Q, n = x.shape
        if n != self.n_in or B != len(self.out_slot):
            raise ValueError(f"expected inputs ({len(self.out_slot)}, Q, {self.n_in}), got {x.shape}")
        blocks = self.blocks
        if blocks and x.dtype != blocks[0][1].dtype:  # x's real type (float32 in f32 runs)
            if x.dtype not in self._cast:
                self._cast[x.dtype] = [(start, W.astype(x.dtype), bias.astype(x.dtype),
                                        resp.astype(x.dtype), act) for start, W, bias, resp, act in blocks]
            blocks = self._cast[x.dtype]
        v = np.zeros((B, Q, self.n_slots), dtype=x.dtype)
        v[:, :, :n] = x
        for (start, W, bias, resp, act), used, srcs in zip(blocks, self._used, self._sources,
                                                          strict=True):
            # each node's weighted inputs summed one by one in slot order (inputs, then earlier
            # nodes by depth and key): the order of `GraphController`, whatever the batch's
            # padding; einsum's grouping of the terms moved with the padding, so a network's
            # outputs depended in the last bits on the batch it was in
            acc = np.zeros((B, Q, W.shape[2]), dtype=x.dtype)
            for s in srcs:
                acc += v[:, :, s, None] * W[:, None, s, :]
            z = bias[:, None, :] + resp[:, None, :] * acc
            out = np.zeros_like(z)
            for a in used:
                m = (act == a)[:, None, :]
                out = np.where(m, NEAT_ACTIVATIONS[ACT_NAMES[a]](z), out)
            v[:, :, start:start + W.shape[2]] = out
        idx = np.broadcast_to(self.out_slot[:, None, :], (B, Q, self.n_out))
        return np.take_along_axis(v, idx, axis=2)


class GraphPolicy:
    """Batched NEAT-network controllers: robot b's observation enters inputs
    [input_offset, input_offset + obs_len) (others 0); its actions are the outputs at
    output_offset + action cell, mapped like the dense controllers (`to_action`).

    With `cell_xy` ((cells, 2) body-cell coordinates) each network is instead queried once per
    actuator, with the actuator cell's (x, y) in inputs 0-1, and output `output_offset` is that
    actuator's action (the direct baseline's "per_cell" layout)."""

    def __init__(self, nets: NetworkBatch, action_cells: Sequence[np.ndarray], action_width: int,
                 input_offset: int = 0, output_offset: int = 0, cell_xy: np.ndarray | None = None):
        self.nets, self.input_offset, self.output_offset = nets, input_offset, output_offset
        B = len(action_cells)
        self.cols = np.full((B, action_width), output_offset, dtype=np.int64)
        for b, cells in enumerate(action_cells):
            self.cols[b, :len(cells)] = output_offset + np.asarray(cells)
        self._rows = np.arange(B)[:, None]
        self.query_xy = None
        if cell_xy is not None:
            self.query_xy = np.zeros((B, action_width, 2))
            for b, cells in enumerate(action_cells):
                self.query_xy[b, :len(cells)] = np.asarray(cell_xy)[np.asarray(cells, dtype=np.int64)]

    def act(self, obs: np.ndarray) -> np.ndarray:
        """(B, D) padded observations -> (B, action_width) actions 1.1 + 0.5 y, in the observations'
        real type; observation entries beyond the networks' inputs are dropped."""
        B, D = obs.shape
        w = min(D, self.nets.n_in - self.input_offset)
        if self.query_xy is None:
            x = np.zeros((B, 1, self.nets.n_in), dtype=obs.dtype)
            x[:, 0, self.input_offset:self.input_offset + w] = obs[:, :w]
            y = self.nets.forward(x)[:, 0, :]
            return to_action(y[self._rows, self.cols])
        x = np.zeros((B, self.query_xy.shape[1], self.nets.n_in), dtype=obs.dtype)
        x[:, :, 0:2] = self.query_xy
        x[:, :, self.input_offset:self.input_offset + w] = obs[:, None, :w]
        return to_action(self.nets.forward(x)[:, :, self.output_offset])
