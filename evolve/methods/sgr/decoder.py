"""SGR decoding: one CPPN genome -> (body matrix, dense controller), HyperNEAT-style.

The body is drawn by the run's body decoder (config key `body_decoder`, evolve/methods/sgr/decoders/;
the default, "substrate", is the paper's: the body network (z > 0) is evaluated on every cell of
the body grid and each cell takes the argmax of its 5 material outputs); the controller network
(z < 0) becomes a `DenseController` whose input grid is sized to the decoded body's observation.
The body reads the CPPN's first `body_outputs` output columns (1, or the "cppn" decoder's 5); with
`cppn_outputs: 1` the controller reads column 0 too, with 2 a column of its own after the body's.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from evolve.methods.sgr.decoders import DEFAULT, body_decoder
from evolve.methods.sgr.hyperneat import Expression, dense_layers, substrate_queries
from evolve.methods.sgr.substrates import controller_side, controller_substrate
from evolve.nn.cppn import CompiledCPPN
from evolve.nn.dense import DenseController
from tasks.env import obs_dim
from tsim.body import build_body, has_actuator, is_connected


@dataclass(frozen=True)
class DecoderSettings:
    """What SGR decoding depends on, from the config: body grid shape (rows, cols), 1 or 2 CPPN
    outputs, the weight expression's threshold and max_weight, the body decoder's name and its
    settings (resolved: `BodyDecoder.resolve`, name-sorted pairs)."""
    shape: tuple[int, int] = (5, 5)
    cppn_outputs: int = 1
    threshold: float = 0.2
    max_weight: float = 1.0
    body_decoder: str = DEFAULT
    body_settings: tuple[tuple[str, Any], ...] = ()

    @property
    def expression(self) -> Expression:
        """The HyperNEAT weight expression built from `threshold` and `max_weight`."""
        return Expression(self.threshold, self.max_weight)

    @property
    def body_outputs(self) -> int:
        """CPPN output columns the body decoder reads (0 .. body_outputs - 1)."""
        return body_decoder(self.body_decoder).body_outputs

    @property
    def n_outputs(self) -> int:
        """The CPPN's outputs: the body's, and the controller's own one with `cppn_outputs: 2`."""
        return self.body_outputs + self.cppn_outputs - 1

    @property
    def controller_output(self) -> int:
        """CPPN output column the controller network reads: 0 when the output is shared, else the
        one after the body's (1 with the paper's substrate)."""
        return 0 if self.cppn_outputs == 1 else self.body_outputs


@dataclass
class Phenotype:
    """A decoded SGR genome: `controller` is None exactly when the body is not a valid robot (such
    genomes are never simulated)."""
    body: np.ndarray
    valid: bool
    controller: DenseController | None = None


@cache
def _controller_queries(k: int, shape: tuple[int, int]):
    return substrate_queries(controller_substrate(k, shape))


def body_from_cppn(cppn: CompiledCPPN, s: DecoderSettings) -> np.ndarray:
    """(H, W) int64 material codes 0-4 drawn by the body decoder `s` names (default: the argmax of
    the paper's body network's 5 outputs at each cell, CPPN output 0); not checked: may be empty,
    disconnected or without an actuator."""
    return body_decoder(s.body_decoder).body(cppn, s.shape, s.expression, dict(s.body_settings))


def is_valid_robot(body: np.ndarray) -> bool:
    """The paper's validity rule: connected and holding at least one actuator."""
    return bool(np.any(body != 0) and is_connected(body) and has_actuator(body))


def controller_from_cppn(cppn: CompiledCPPN, body: np.ndarray, task: str,
                         s: DecoderSettings) -> DenseController:
    """The controller network for `body` on `task`: its k x k input grid fits the body's
    observation, and its actions are the outputs at the body's actuator cells in evogym's order."""
    b = build_body(body)
    n_obs = obs_dim(task, b.n_points)
    q, slices = _controller_queries(controller_side(n_obs), s.shape)
    W1, b1, W2, b2 = dense_layers(cppn(q, (s.controller_output,))[:, 0], slices, s.expression)
    act = controller_substrate(controller_side(n_obs), s.shape).activations
    return DenseController([W1, W2], [b1, b2], list(act), n_obs, b.actuator_flat.copy())


def decode(genome, genome_config, task: str, s: DecoderSettings) -> Phenotype:
    """Genome -> Phenotype; the controller is built only for a valid robot (valid=False and no
    controller otherwise)."""
    cppn = CompiledCPPN(genome, genome_config)
    body = body_from_cppn(cppn, s)
    if not is_valid_robot(body):
        return Phenotype(body, False)
    return Phenotype(body, True, controller_from_cppn(cppn, body, task, s))
