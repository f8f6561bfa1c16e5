"""Batched fitness: every robot of a generation in one `BatchEnv`, controllers in one forward pass.

Shared by all methods; a robot's fitness is its episode return in evogym's reward units.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evolve.controller import ControllerBatch, DenseController
from tasks.env import BatchEnv


def rollout(task: str, bodies: Sequence[np.ndarray], controllers: Sequence[DenseController],
            episode_steps: int | str | None = None) -> np.ndarray:
    """Episode return of each (body, controller) pair, simulated together."""
    if len(bodies) != len(controllers):
        raise ValueError(f"{len(bodies)} bodies but {len(controllers)} controllers")
    if len(bodies) == 0:
        return np.zeros(0)
    env = BatchEnv(task, list(bodies), episode_steps=episode_steps)
    policy = ControllerBatch(controllers, env.max_obs_dim, env.sim.max_actuators)
    obs = env.reset()
    total = np.zeros(env.n_worlds)
    for _ in range(env.episode_steps):
        obs, r, term, trunc, _ = env.step(policy.act(obs))
        total += r
        if np.all(term | trunc):
            break
    return total
