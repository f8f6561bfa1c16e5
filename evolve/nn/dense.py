"""Plain dense controllers and their batched forward pass inside the simulation loop.

A controller maps a robot's evogym observation to one output per body cell; the robot's actions
are the outputs at its actuator cells in evogym's actuator order, mapped from tanh's (-1, 1) onto
evogym's action range: action = 1.1 + 0.5 * y, i.e. (0.6, 1.6).
The JSON form holds everything needed to run a controller with numpy alone (no neat-python).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from evolve.nn.activations import PLAIN_ACTIVATIONS, to_action

FORMAT = "sgr-dense-controller-1"  # `to_json`


@dataclass
class DenseController:
    """Layers y = act(x @ W + b). `input_size` is the observation length; the first layer may have
    more rows (the zero-padded k x k input grid), which multiply zeros."""

    weights: list[np.ndarray]
    biases: list[np.ndarray]
    activations: list[str]
    input_size: int
    action_cells: np.ndarray  # flat body-cell index of each actuator, evogym's action order

    def __repr__(self) -> str:
        sizes = " -> ".join([str(self.input_size), *(str(w.shape[1]) for w in self.weights)])
        return (f"DenseController({sizes}, {len(self.action_cells)} actuators, "
                f"activations {'/'.join(self.activations)})")

    def outputs(self, obs: np.ndarray) -> np.ndarray:
        """The last layer's values (one per body cell) for one robot's unpadded observation (length
        `input_size`)."""
        x = np.zeros(self.weights[0].shape[0])
        x[:self.input_size] = obs
        for W, b, a in zip(self.weights, self.biases, self.activations, strict=True):
            x = PLAIN_ACTIVATIONS[a](x @ W + b)
        return x

    def act(self, obs: np.ndarray) -> np.ndarray:
        """One robot's actions, computed exactly as evolution computed them (`ControllerBatch`,
        bit for bit): a champion's episode is often chaotic, and the ~1e-16 rounding difference of
        another summation order (`reference_act`) can change its return completely. In the
        observation's real type (float32 in an f32 process, as evolution there), else float64."""
        obs = np.asarray(obs)
        obs = obs if obs.dtype == np.float32 else obs.astype(np.float64, copy=False)
        if obs.shape != (self.input_size,):
            raise ValueError(f"controller expects an observation of length {self.input_size}, "
                             f"got {obs.shape}")
        return ControllerBatch([self], len(obs), len(self.action_cells)).act(obs[None, :])[0]

    def reference_act(self, obs: np.ndarray) -> np.ndarray:
        """The slow, obvious forward pass for one robot (the test oracle of `ControllerBatch`)."""
        return to_action(self.outputs(obs)[self.action_cells])

    def to_json(self) -> dict:
        """Self-contained JSON (format sgr-dense-controller-1, with a `doc` of the semantics),
        runnable with numpy alone."""
        return {"format": FORMAT,
                "input_size": self.input_size,
                "input_padding": int(self.weights[0].shape[0]) - self.input_size,
                "layers": [{"weights": W.tolist(), "biases": b.tolist(), "activation": a}
                           for W, b, a in zip(self.weights, self.biases, self.activations, strict=True)],
                "action_cells": self.action_cells.tolist(),
                "action_map": "action = 1.1 + 0.5 * output[action_cells]",
                "doc": "x = observation zero-padded by input_padding; for each layer x = "
                       "activation(x @ weights + biases) (weights are [in][out])"}

    @classmethod
    def from_json(cls, d: dict) -> DenseController:
        """Inverse of `to_json`; the `format` key is not checked."""
        layers = d["layers"]
        return cls([np.asarray(L["weights"], dtype=np.float64) for L in layers],
                   [np.asarray(L["biases"], dtype=np.float64) for L in layers],
                   [L["activation"] for L in layers], int(d["input_size"]),
                   np.asarray(d["action_cells"], dtype=np.int64))


class ControllerBatch:
    """Every robot's controller evaluated together: padded (B, in, out) weight stacks, einsum."""

    def __init__(self, controllers: Sequence[DenseController], obs_width: int, action_width: int):
        B = len(controllers)
        n_layers = len(controllers[0].weights)
        if any(len(c.weights) != n_layers for c in controllers):
            raise ValueError("all controllers of a batch need the same number of layers")
        self.activations = controllers[0].activations
        self.Ws, self.bs = [], []
        for layer in range(n_layers):
            rows = obs_width if layer == 0 else max(c.weights[layer].shape[0] for c in controllers)
            cols = max(c.weights[layer].shape[1] for c in controllers)
            W = np.zeros((B, rows, cols))
            b = np.zeros((B, cols))
            for i, c in enumerate(controllers):
                w = c.weights[layer][:c.input_size] if layer == 0 else c.weights[layer]
                W[i, :w.shape[0], :w.shape[1]] = w
                b[i, :w.shape[1]] = c.biases[layer]
            self.Ws.append(W)
            self.bs.append(b)
        self.cells = np.zeros((B, action_width), dtype=np.int64)
        for i, c in enumerate(controllers):
            self.cells[i, :len(c.action_cells)] = c.action_cells
        self._rows = np.arange(B)[:, None]
        self._cast: dict = {}  # dtype -> the weights and biases rounded to it

    def act(self, obs: np.ndarray) -> np.ndarray:
        """(B, obs_width) padded observations -> (B, action_width) padded actions, computed in the
        observations' real type (float32 in an f32 process: weights rounded to it once)."""
        x = obs
        Ws, bs = self.Ws, self.bs
        if obs.dtype != Ws[0].dtype:
            if obs.dtype not in self._cast:
                self._cast[obs.dtype] = ([W.astype(obs.dtype) for W in Ws], [b.astype(obs.dtype) for b in bs])
            Ws, bs = self._cast[obs.dtype]
        for W, b, a in zip(Ws, bs, self.activations, strict=True):
            x = PLAIN_ACTIVATIONS[a](np.einsum("bi,bio->bo", x, W) + b)
        return to_action(x[self._rows, self.cells])
