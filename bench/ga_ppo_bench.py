"""One generation of evogym's GA co-design: N bodies, each trained by PPO for T timesteps.

Both sides use evogym's PPO arguments (examples/ppo/args.py: 1 env per body, n_steps 128, batch 4,
4 epochs, ...) on Walker-v0 (evogym's 500-step episodes) and the same N random 5x5 bodies:
- sgr: `--method ga-ppo`'s generation (evolve/rollout/ppo.py): the N bodies trained together in
  one batched simulation, each with its own policy, then each trained policy's deterministic
  episode;
- evogym's loop: its run_ga.py trains each body with stable-baselines3's PPO in its own process
  (SB3's make_vec_env, 1 env), num_cores bodies at a time. It is run here on sgr.evogym, whose env
  steps faster than evogym's (so the ratio is a lower bound on the one against evogym itself), in
  as many processes as the machine has cores, each training one body for --base-timesteps; the
  generation's seconds are N x T over their summed rate. Twice: with torch's default threads (what
  run_ga.py does: each process takes every core) and with one torch thread per process (the best
  case for evogym's loop, which the speed-up is taken against).
Kernels are compiled and torch is imported before the clocks start.

    python bench/ga_ppo_bench.py                          # 16 bodies x 20,000 timesteps
    python bench/ga_ppo_bench.py --bodies 64 --timesteps 5000
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

EVOGYM_PPO = dict(learning_rate=2.5e-4, n_steps=128, batch_size=4, n_epochs=4, gamma=0.99, gae_lambda=0.95,
                  clip_range=0.1, ent_coef=0.01, vf_coef=0.5, max_grad_norm=0.5)


def bodies(n: int) -> list[np.ndarray]:
    """n random bodies as evogym samples them (its GA's first generation), seed 0."""
    import random

    from sgr.evogym import sample_robot

    random.seed(0)
    return [sample_robot((5, 5))[0].astype(np.int64) for _ in range(n)]


def ours(n: int, timesteps: int) -> dict:
    """sgr's generation: train the n bodies in one batch, then score each trained policy."""
    from evolve.nn.mlp import mlp_policy
    from evolve.rollout.episodes import rollout_policy
    from evolve.rollout.ppo import PpoSettings, train_bodies

    bs = bodies(n)
    warm = PpoSettings(timesteps=128)
    train_bodies("Walker-v0", bs, warm, seed=1, episode_steps="evogym")  # kernels compiled, torch loaded
    s = PpoSettings(timesteps=timesteps, **{k: v for k, v in EVOGYM_PPO.items()})
    t0 = time.perf_counter()
    trained = train_bodies("Walker-v0", bs, s, seed=0, episode_steps="evogym")
    t1 = time.perf_counter()
    ctrls = [t.controller for t in trained]
    returns = rollout_policy("Walker-v0", bs, lambda env: mlp_policy(env, ctrls), "evogym")
    t2 = time.perf_counter()
    steps = n * trained[0].timesteps
    return {"bodies": n, "timesteps": trained[0].timesteps, "train_s": t1 - t0, "score_s": t2 - t1,
            "seconds": t2 - t0, "steps_per_s": steps / (t2 - t0), "best_return": float(np.max(returns))}


def _sb3_one(args: tuple) -> float:
    """One process of evogym's loop: SB3's PPO on one body, 1 env; its learn's seconds."""
    body, timesteps, threads = args
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    import sgr.evogym.envs  # noqa: F401  (evogym's bare ids)
    from sgr.evogym.utils import get_full_connectivity

    if threads:
        torch.set_num_threads(threads)
    env = make_vec_env("Walker-v0", n_envs=1, seed=42,
                       env_kwargs={"body": body, "connections": get_full_connectivity(body)})
    env.reset()
    for _ in range(3):  # kernels compiled before the clock
        env.step(np.stack([env.action_space.sample()]))
    model = PPO("MlpPolicy", env, seed=0, device="cpu", verbose=0, **EVOGYM_PPO)
    t0 = time.perf_counter()
    model.learn(timesteps)
    return time.perf_counter() - t0


def evogym_loop(n: int, timesteps: int, base: int, cores: int, threads: int | None) -> dict:
    """evogym's run_ga.py loop on sgr.evogym: `cores` processes at once, each one body for `base`
    timesteps (`threads`: torch's threads per process; None: torch's default); the generation of n
    bodies x `timesteps` estimated from their summed rate."""
    import multiprocessing as mp

    with mp.get_context("spawn").Pool(cores) as pool:
        seconds = pool.map(_sb3_one, [(b, base, threads) for b in bodies(cores)])
    rate = sum(base / s for s in seconds)
    return {"processes": cores, "torch_threads": threads or "default", "timesteps_each": base,
            "seconds_each": seconds, "steps_per_s": rate, "generation_s": n * timesteps / rate}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--bodies", type=int, default=16)
    p.add_argument("--timesteps", type=int, default=20_000, help="per body")
    p.add_argument("--base-timesteps", type=int, default=2048, help="per process of evogym's loop")
    p.add_argument("--cores", type=int, default=os.cpu_count() or 1, help="evogym's num_cores")
    p.add_argument("--record", help="write the figures as JSON here")
    p.add_argument("--evogym-python", help="the Python of a venv with evogym 2.0 and SB3: evogym's loop in "
                                           "evogym itself (bench/evogym_side.py) instead of on sgr.evogym")
    a = p.parse_args(argv)
    from tasks.records import cpu_model

    print(f"# {cpu_model()}; Walker-v0, {a.bodies} random 5x5 bodies x {a.timesteps:,} timesteps, "
          "evogym's PPO arguments", flush=True)
    loops = {}
    where = "in evogym" if a.evogym_python else "on sgr.evogym"
    for threads in (None, 1):
        if a.evogym_python:
            from bench.evogym_side import run_side

            r = run_side(a.evogym_python, "ga-loop", "--cores", str(a.cores), "--timesteps",
                         str(a.base_timesteps), "--threads", str(threads or 0))
            r["generation_s"] = a.bodies * a.timesteps / r["steps_per_s"]
        else:
            r = evogym_loop(a.bodies, a.timesteps, a.base_timesteps, a.cores, threads)
        loops[threads] = r
        print(f"evogym's loop {where}: {r['processes']} processes x {a.base_timesteps:,} steps, torch "
              f"threads {r['torch_threads']}: {r['steps_per_s']:7.0f} learn steps/s -> "
              f"{r['generation_s']:8.1f} s a generation", flush=True)
    base, default = loops[1], loops[None]
    mine = ours(a.bodies, a.timesteps)
    print(f"sgr ga-ppo, one batch:       {mine['steps_per_s']:7.0f} learn steps/s -> "
          f"{mine['seconds']:8.1f} s "
          f"a generation (train {mine['train_s']:.1f} s, score {mine['score_s']:.1f} s); "
          f"{base['generation_s'] / mine['seconds']:.1f}x", flush=True)
    if a.record:
        from tasks.records import figure, write_record

        figures = {"evogym_loop_default_threads_steps_per_s": figure(default["steps_per_s"], "steps/s"),
                   "evogym_loop_steps_per_s": figure(base["steps_per_s"], "steps/s"),
                   "evogym_loop_generation_s": figure(base["generation_s"], "s"),
                   "ga_ppo_steps_per_s": figure(mine["steps_per_s"], "steps/s"),
                   "ga_ppo_generation_s": figure(mine["seconds"], "s"),
                   "speedup": figure(base["generation_s"] / mine["seconds"], "x")}
        write_record(a.record, None, figures, evogym_loop=base, evogym_loop_default_threads=default,
                     ga_ppo=mine, evogym_loop_runs=where)
        print(f"wrote {a.record}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
