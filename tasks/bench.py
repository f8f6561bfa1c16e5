"""Throughput benchmark: random valid 5x5 bodies (fixed seed), sinusoidal open-loop actions."""

from __future__ import annotations

import time

import numpy as np

from tasks.env import BatchEnv
from tsim.backend import runtime
from tsim.sampling import sample_robots


def sinusoid(t: int, n_act: int, period: float = 20.0) -> np.ndarray:
    """(n_act,) open-loop actions at step t: 1.1 + 0.5 sin(2 pi t / period + phase), phases spread
    evenly over the actuators; always inside evogym's [0.6, 1.6], so nothing is clipped."""
    phase = 2 * np.pi * np.arange(n_act) / max(n_act, 1)
    return 1.1 + 0.5 * np.sin(2 * np.pi * t / period + phase)


def bench(task: str = "Walker-v0", robots: int = 128, steps: int = 100, seed: int = 0) -> dict:
    """Time `steps` env steps of `robots` random 5x5 robots; compilation and the first step are
    excluded."""
    if robots < 1 or steps < 1:
        raise ValueError("robots and steps must be >= 1")
    rng = np.random.default_rng(seed)
    return bench_bodies(task, list(sample_robots(robots, (5, 5), rng)), steps)


def bench_bodies(task: str, bodies: list[np.ndarray], steps: int, physics: bool = True) -> dict:
    """`bench` on given bodies (any sizes); `physics` also times `BatchSim.step` alone."""
    robots = len(bodies)
    t0 = time.perf_counter()
    env = BatchEnv(task, bodies, episode_steps=steps + 1)
    A = env.sim.max_actuators
    env.step(np.ones((robots, A)))  # compiles the kernel (or loads it from Taichi's cache)
    compile_s = time.perf_counter() - t0
    acts = [sinusoid(t, A)[None, :].repeat(robots, 0) for t in range(steps)]
    t0 = time.perf_counter()
    for t in range(steps):
        env.step(acts[t])
    wall = time.perf_counter() - t0
    out = {"robot_steps_per_s": robots * steps / wall, "compile_s": compile_s,
           "threads": runtime.threads(), "pinned": len(runtime.PINNED) > 0, "robots": robots,
           "precision": runtime.precision(),
           "steps": steps, "task": task}
    if physics:  # no observations or rewards
        env.reset()
        t1 = time.perf_counter()
        for t in range(steps):
            env.sim.set_actions(acts[t])
            env.sim.step()
        out["physics_robot_steps_per_s"] = robots * steps / (time.perf_counter() - t1)
    return out
