"""Trained MLP controllers (a PPO policy's mean action) and their batched forward pass.

A controller is the actor of an actor-critic as stable-baselines3's `MlpPolicy` builds it: tanh
hidden layers, then a linear layer giving the mean action; the deterministic action is that mean
clipped to evogym's action range [0.6, 1.6]. The JSON form holds the weights in full and runs with
numpy alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

FORMAT = "sgr-mlp-controller-1"  # `to_json`
ACTION_LOW, ACTION_HIGH = 0.6, 1.6  # evogym's action space


@dataclass
class MlpController:
    """Layers x = tanh(x @ W + b), the last one linear; actions = clip(x[:n_actions], 0.6, 1.6).

    Args:
        weights: (in, out) per layer; the first has `input_size` rows, the last `n_actions` columns.
        biases: (out,) per layer.
        input_size: the observation's length.
        n_actions: the body's actuators, in evogym's action order.
    """

    weights: list[np.ndarray]
    biases: list[np.ndarray]
    input_size: int
    n_actions: int

    def __post_init__(self) -> None:
        if not self.weights or len(self.weights) != len(self.biases):
            raise ValueError("an MLP controller needs as many bias vectors as weight matrices, at least one")
        for i, (W, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            if W.ndim != 2 or b.shape != (W.shape[1],):
                raise ValueError(f"layer {i}: weights {W.shape} and biases {b.shape} do not fit")
            if i and W.shape[0] != self.weights[i - 1].shape[1]:
                raise ValueError(f"layer {i}: {W.shape[0]} inputs after "
                                 f"{self.weights[i - 1].shape[1]} outputs")
        if self.weights[0].shape[0] != self.input_size or self.weights[-1].shape[1] != self.n_actions:
            raise ValueError(f"weights of {self.weights[0].shape[0]} inputs and {self.weights[-1].shape[1]} "
                             f"outputs for {self.input_size} observations and {self.n_actions} actions")
        if not all(np.isfinite(W).all() and np.isfinite(b).all() for W, b in zip(self.weights, self.biases,
                                                                                  strict=True)):
            raise ValueError("an MLP controller's weights must be finite")

    def __repr__(self) -> str:
        sizes = " -> ".join([str(self.input_size), *(str(w.shape[1]) for w in self.weights)])
        return f"MlpController({sizes}, tanh)"

    def act(self, obs: np.ndarray) -> np.ndarray:
        """One robot's actions for its observation (length `input_size`), computed as a batch of one
        (`MlpBatch`), so bit for bit as in evolution."""
        obs = np.asarray(obs, dtype=np.float64)
        if obs.shape != (self.input_size,):
            raise ValueError(f"controller expects an observation of length {self.input_size}, "
                             f"got {obs.shape}")
        return MlpBatch([self], self.input_size, self.n_actions).act(obs[None, :])[0]

    def reference_act(self, obs: np.ndarray) -> np.ndarray:
        """The slow, obvious forward pass (the test oracle of `MlpBatch`)."""
        x = np.asarray(obs, dtype=np.float64)
        for i, (W, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            x = x @ W + b
            if i < len(self.weights) - 1:
                x = np.tanh(x)
        return np.clip(x, ACTION_LOW, ACTION_HIGH)

    def to_json(self) -> dict:
        """Self-contained JSON (format sgr-mlp-controller-1, with a `doc` of the semantics)."""
        return {"format": FORMAT, "input_size": self.input_size, "n_actions": self.n_actions,
                "layers": [{"weights": W.tolist(), "biases": b.tolist()}
                           for W, b in zip(self.weights, self.biases, strict=True)],
                "doc": "x = observation; for each layer x = x @ weights + biases ([in][out]), tanh after "
                       "every layer but the last; actions = clip(x, 0.6, 1.6) in evogym's actuator order"}

    @classmethod
    def from_json(cls, d: dict) -> MlpController:
        """Inverse of `to_json`; ValueError (or KeyError, TypeError) when it is not one."""
        layers = d["layers"]
        if not isinstance(layers, list):
            raise TypeError("'layers' must be a list")
        ws = [np.asarray(L["weights"], dtype=np.float64) for L in layers]
        bs = [np.asarray(L["biases"], dtype=np.float64) for L in layers]
        size, n = d["input_size"], d["n_actions"]
        if not all(type(v) is int and v >= 1 for v in (size, n)):
            raise ValueError(f"input_size and n_actions must be positive ints, got {size!r}, {n!r}")
        return cls(ws, bs, size, n)


class MlpBatch:
    """Every robot's MLP controller evaluated together: zero-padded (B, in, out) weight stacks and
    einsum, whose sums run in one order whatever the batch and its padding (a robot's actions are
    the same bits alone or in any batch)."""

    def __init__(self, controllers: Sequence[MlpController], obs_width: int, action_width: int):
        n_layers = len(controllers[0].weights)
        if any(len(c.weights) != n_layers for c in controllers):
            raise ValueError("all controllers of a batch need the same number of layers")
        B = len(controllers)
        self.Ws, self.bs = [], []
        for layer in range(n_layers):
            rows = obs_width if layer == 0 else max(c.weights[layer].shape[0] for c in controllers)
            last = layer == n_layers - 1
            cols = action_width if last else max(c.weights[layer].shape[1] for c in controllers)
            W, b = np.zeros((B, rows, cols)), np.zeros((B, cols))
            for i, c in enumerate(controllers):
                w = c.weights[layer]
                W[i, :w.shape[0], :w.shape[1]] = w
                b[i, :w.shape[1]] = c.biases[layer]
            self.Ws.append(W)
            self.bs.append(b)

    def act(self, obs: np.ndarray) -> np.ndarray:
        """(B, obs_width) zero-padded observations -> (B, action_width) actions (padding: 0.6)."""
        x = np.asarray(obs, dtype=np.float64)
        last = len(self.Ws) - 1
        for i, (W, b) in enumerate(zip(self.Ws, self.bs, strict=True)):
            x = np.einsum("bi,bio->bo", x, W) + b
            if i < last:
                x = np.tanh(x)
        return np.clip(x, ACTION_LOW, ACTION_HIGH)


def mlp_policy(env, controllers: Sequence[MlpController]) -> MlpBatch:
    """The batched policy of MLP controllers driving the robots of `env` (a picklable factory for
    `RolloutPool`)."""
    return MlpBatch(controllers, env.max_obs_dim, env.sim.max_actuators)
