"""Steps per second on the paths evogym users take, for evogym or for sgr.evogym (the same script
runs under either: `--lib evogym` with evogym's venv, `--lib sgr` with ours), one process:

  make    gym.make(TASK, body=...) of a bare id, then env.step (evogym's own envs / sgr's TaskEnv)
  custom  evogym's tutorial env (tutorials/envs/simple_env.py: an EvoGymBase subclass whose step
          reads object_pos_at_time before and after, and get_vel_com_obs / get_relative_pos_obs)
  sim     a plain EvoSim loop: set_action, step, object_pos_at_time(get_time(), 'robot')
  vec     (sgr only) gym.make_vec(TASK, num_envs=N): robot-steps/s of the batched vector env

Bodies: evogym's sample_robot((5, 5)) after random.seed(s), s = 0..N-1; actions
1.1 + 0.5 sin(2 pi t / 20 + j) (as ../shared/tools/evogym_speed.py). Prints one line per path:
path, steps/s per CPU second of the process. Pin it to one core for per-core figures:
taskset -c 1 ... (sgr: SGR_THREADS=1, one Taichi thread).

    SGR_THREADS=1 taskset -c 1 .venv/bin/python bench/evogym_api_speed.py --lib sgr
    taskset -c 1 ~/.cache/evogym-venv/bin/python bench/evogym_api_speed.py --lib evogym
"""

from __future__ import annotations

import argparse
import importlib
import json
import random
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
WORLD = HERE.parent / "tests" / "data" / "evogym_api" / "simple_walker_env.json"


def _clock() -> float:
    """CPU seconds of this process (all its threads): on a shared machine, wall time measures the
    other processes too; CPU time is what one core spends on this one."""
    return time.process_time()


def _actions(t: int, n: int) -> np.ndarray:
    return 1.1 + 0.5 * np.sin(2 * np.pi * t / 20 + np.arange(n))


def _bodies(evogym, n: int) -> list:
    out = []
    for s in range(n):
        random.seed(s)
        np.random.seed(s)
        out.append(evogym.sample_robot((5, 5)))
    return out


def bench_make(evogym, task: str, bodies, steps: int) -> float:
    import gymnasium as gym
    importlib.import_module(f"{evogym.__name__}.envs")
    total, elapsed = 0, 0.0
    for body, _ in bodies:
        env = gym.make(task, body=body)
        env.reset(seed=0)
        n = env.action_space.shape[0]
        t0 = _clock()
        for t in range(steps):
            term = env.step(_actions(t, n))[2]
            total += 1
            if term:
                break
        elapsed += _clock() - t0
        env.close()
    return total / elapsed


def _simple_env_class(evogym):
    """The tutorial's SimpleWalkerEnvClass (our port of it, with its imports pointed at `evogym`),
    over the world file given here instead of the tutorial's relative path."""
    envs = importlib.import_module(f"{evogym.__name__}.envs")
    from gymnasium import spaces

    class SimpleWalkerEnvClass(envs.EvoGymBase):
        def __init__(self, body, connections=None, render_mode=None, render_options=None):
            self.world = evogym.EvoWorld.from_json(str(WORLD))
            self.world.add_from_array("robot", body, 1, 1, connections=connections)
            envs.EvoGymBase.__init__(self, world=self.world, render_mode=render_mode,
                                     render_options=render_options)
            n = self.get_actuator_indices("robot").size
            obs_size = self.reset()[0].size
            self.action_space = spaces.Box(low=0.6, high=1.6, shape=(n,), dtype=float)
            self.observation_space = spaces.Box(low=-100.0, high=100.0, shape=(obs_size,), dtype=float)

        def step(self, action):
            pos_1 = self.object_pos_at_time(self.get_time(), "robot")
            done = super().step({"robot": action})
            pos_2 = self.object_pos_at_time(self.get_time(), "robot")
            reward = np.mean(pos_2, 1)[0] - np.mean(pos_1, 1)[0]
            if done:
                reward -= 3.0
            if np.mean(pos_2, 1)[0] > 28:
                done = True
                reward += 1.0
            obs = np.concatenate((self.get_vel_com_obs("robot"), self.get_relative_pos_obs("robot")))
            return obs, reward, done, False, {}

        def reset(self, seed=None, options=None):
            super().reset(seed=seed, options=options)
            return np.concatenate((self.get_vel_com_obs("robot"), self.get_relative_pos_obs("robot"))), {}

    return SimpleWalkerEnvClass


def bench_custom(evogym, bodies, steps: int) -> float:
    cls = _simple_env_class(evogym)
    total, elapsed = 0, 0.0
    for body, conn in bodies:
        env = cls(body, conn)
        env.reset()
        n = env.action_space.shape[0]
        t0 = _clock()
        for t in range(steps):
            done = env.step(_actions(t, n))[2]
            total += 1
            if done:
                break
        elapsed += _clock() - t0
    return total / elapsed


def bench_sim(evogym, bodies, steps: int) -> float:
    total, elapsed = 0, 0.0
    for body, conn in bodies:
        world = evogym.EvoWorld.from_json(str(WORLD))
        world.add_from_array("robot", body, 1, 1, connections=conn)
        sim = evogym.EvoSim(world)
        sim.reset()
        n = sim.get_dim_action_space("robot")
        t0 = _clock()
        for t in range(steps):
            sim.set_action("robot", _actions(t, n))
            if sim.step():
                break
            sim.object_pos_at_time(sim.get_time(), "robot")
            total += 1
        elapsed += _clock() - t0
    return total / elapsed


def bench_vec(evogym, task: str, bodies, steps: int) -> float:
    import gymnasium as gym
    importlib.import_module(f"{evogym.__name__}.envs")
    vec = gym.make_vec(task, bodies=[b for b, _ in bodies])
    vec.reset(seed=0)
    n = vec.single_action_space.shape[0]
    t0 = _clock()
    for t in range(steps):
        vec.step(np.tile(_actions(t, n), (vec.num_envs, 1)))
    return steps * vec.num_envs / (_clock() - t0)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--lib", choices=["evogym", "sgr"], required=True)
    p.add_argument("--task", default="Walker-v0")
    p.add_argument("--robots", type=int, default=8)
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--vec-robots", type=int, default=128)
    p.add_argument("--paths", nargs="*", default=["make", "custom", "sim", "vec"])
    args = p.parse_args()
    if args.lib == "sgr":
        sys.path.insert(0, str(HERE.parent))
    evogym = importlib.import_module("evogym" if args.lib == "evogym" else "sgr.evogym")
    bodies = _bodies(evogym, args.robots)
    # warm-up, untimed: sgr compiles a kernel for each capacity tier its bodies need on first use
    # (once per process, ~2-4 s each); every body takes one step first
    for path in ("make", "custom", "sim"):
        if path in args.paths:
            {"make": lambda: bench_make(evogym, args.task, bodies, 1),
             "custom": lambda: bench_custom(evogym, bodies, 1),
             "sim": lambda: bench_sim(evogym, bodies, 1)}[path]()
    out = {}
    for path in args.paths:
        if path == "make":
            out[path] = bench_make(evogym, args.task, bodies, args.steps)
        elif path == "custom":
            out[path] = bench_custom(evogym, bodies, args.steps)
        elif path == "sim":
            out[path] = bench_sim(evogym, bodies, args.steps)
        elif path == "vec" and args.lib == "sgr":
            out[path] = bench_vec(evogym, args.task, _bodies(evogym, args.vec_robots), args.steps)
        if path in out:
            print(f"{path} {out[path]:.1f}", flush=True)
    print(json.dumps({"lib": args.lib, "task": args.task, **{k: round(v, 1) for k, v in out.items()}}))


if __name__ == "__main__":
    main()
