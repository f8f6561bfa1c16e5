"""Batched fitness: every robot of a generation in one `BatchEnv`, controllers in one forward pass.

Shared by all methods; a robot's fitness is its episode return in evogym's reward units.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np

from evolve.nn.dense import ControllerBatch, DenseController
from evolve.rollout.robust import EpisodeNoise
from tasks.behaviour import BehaviourRecorder
from tasks.env import BatchEnv


class BatchPolicy(Protocol):
    """What a policy factory returns: one `act` call per env step drives the whole batch."""
    def act(self, obs: np.ndarray) -> np.ndarray:
        """(B, max_obs_dim) padded observations -> (B, max_actuators) padded actions."""


def rollout_policy(task: str, bodies: Sequence[np.ndarray], make_policy: Callable[[BatchEnv], BatchPolicy],
                   episode_steps: int | str | None = None, noise: EpisodeNoise | None = None, *,
                   precision: str | None = None, record: bool = False) -> np.ndarray:
    """Episode return of every body driven by the batched policy built for the env's layout;
    `noise` perturbs each world's episode (robust evaluation, evolve/rollout/robust.py). With
    `record`, (B, 1 + len(FEATURES)): each return, then its behaviour features
    (tasks/behaviour.py); without, the episode runs exactly as it always has.

    Every world's random stream starts from the same seed (0): a task with per-episode randomness
    (BidirectionalWalker-v0's goals) then gives every robot the same episode, so a robot's fitness
    depends on the robot alone, not on its slot in the batch or the worker count, and a champion
    replayed alone (world 0, seed 0) scores what it scored in evolution. `precision`: the real type
    to simulate in (a champion's replay passes its own; None: the process's)."""
    if len(bodies) == 0:
        return np.zeros(0)
    env = BatchEnv(task, list(bodies), episode_steps=episode_steps, seeds=[0] * len(bodies),
                   robot_shift=None if noise is None else noise.shifts(), precision=precision)
    policy = make_policy(env)
    obs = env.observe()  # the constructed env's episode: its stream's first draw, as in a replay
    total = np.zeros(env.n_worlds)
    recorder = BehaviourRecorder(env) if record else None
    for t in range(env.episode_steps):
        act = policy.act(obs)
        wanted = act
        if noise is not None:
            extra = noise.actions(t, act.shape[1])
            if extra is not None:
                act = act + extra
        running = None if recorder is None else ~env.terminated
        obs, r, term, trunc, info = env.step(act)
        total += r
        if recorder is not None:
            recorder.step(wanted, running & ~info["unstable"])
        if np.all(term | trunc):
            break
    if recorder is not None:
        return np.column_stack([total, recorder.features()])
    return total


def dense_policy(env: BatchEnv, controllers: Sequence[DenseController]) -> ControllerBatch:
    """The batched policy of dense controllers (a picklable factory for `RolloutPool`)."""
    return ControllerBatch(controllers, env.max_obs_dim, env.sim.max_actuators)

