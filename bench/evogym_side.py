"""evogym's side of the RL benchmarks, run with the Python of a venv that has evogym 2.0 and
stable-baselines3 (not sgr's): `bench/rl_bench.py`, `bench/rl_learn.py` and `bench/ga_ppo_bench.py`
call it with `--evogym-python PATH` and read the JSON it prints last. It imports nothing of sgr.

    PY=/path/to/evogym-venv/bin/python
    $PY bench/evogym_side.py learn-speed --timesteps 4096       # evogym's example loop, steps/s
    $PY bench/evogym_side.py ga-loop --cores 2 --timesteps 2048 --threads 1
    $PY bench/evogym_side.py learn-curve --timesteps 100000     # deterministic return vs seconds

evogym's example loop is its examples/ppo/run.py: SB3's make_vec_env over evogym's id, one env,
evogym's PPO arguments (examples/ppo/args.py); the body is evogym's speed_bot
(examples/world_data/speed_bot.json) for the learning figures, random 5x5 bodies drawn by evogym's
sample_robot after random.seed(0) for the GA loop (its run_ga.py's first generation).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

SPEED_BOT = np.array([[2, 3, 3, 3, 1], [1, 3, 3, 3, 1], [3, 1, 0, 1, 3], [3, 0, 0, 0, 3]])
EVOGYM_PPO = dict(learning_rate=2.5e-4, n_steps=128, batch_size=4, n_epochs=4, gamma=0.99, gae_lambda=0.95,
                  clip_range=0.1, ent_coef=0.01, vf_coef=0.5, max_grad_norm=0.5)


def run_side(python: str, *args: str) -> dict:
    """Run this script with evogym's `python` (from sgr's side) and return the JSON it printed last;
    SystemExit naming what failed."""
    import subprocess
    import sys
    from pathlib import Path

    r = subprocess.run([python, str(Path(__file__).resolve()), *args], capture_output=True, text=True)
    if r.returncode:
        sys.exit(f"evogym's side failed ({python} {' '.join(args)}): {r.stderr.strip()[-600:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def example_loop(body, seed: int = 0, threads: int | None = None):
    """evogym's run_ppo: SB3's make_vec_env over evogym's Walker-v0, one env, and its PPO."""
    import evogym.envs  # noqa: F401
    import torch
    from evogym import get_full_connectivity
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    if threads:
        torch.set_num_threads(threads)
    env = make_vec_env("Walker-v0", n_envs=1, seed=seed,
                       env_kwargs={"body": body, "connections": get_full_connectivity(body)})
    env.reset()
    for _ in range(3):
        env.step(np.stack([env.action_space.sample()]))
    return PPO("MlpPolicy", env, seed=seed, device="cpu", verbose=0, **EVOGYM_PPO)


def learn_speed(timesteps: int) -> dict:
    model = example_loop(SPEED_BOT)
    t0 = time.perf_counter()
    model.learn(timesteps)
    wall = time.perf_counter() - t0
    return {"timesteps": int(model.num_timesteps), "seconds": wall, "steps_per_s": model.num_timesteps / wall}


def _one(args: tuple) -> float:
    body, timesteps, threads = args
    model = example_loop(body, seed=42, threads=threads)
    t0 = time.perf_counter()
    model.learn(timesteps)
    return time.perf_counter() - t0


def ga_loop(cores: int, timesteps: int, threads: int | None) -> dict:
    """run_ga.py's loop: `cores` processes at once, each training one body."""
    import multiprocessing as mp
    import random

    from evogym import sample_robot

    random.seed(0)
    bodies = [sample_robot((5, 5))[0] for _ in range(cores)]
    with mp.get_context("spawn").Pool(cores) as pool:
        seconds = pool.map(_one, [(b, timesteps, threads) for b in bodies])
    return {"processes": cores, "torch_threads": threads or "default", "timesteps_each": timesteps,
            "seconds_each": seconds, "steps_per_s": sum(timesteps / s for s in seconds)}


def deterministic_return(model, steps: int = 500) -> float:
    """One 500-step episode of the deterministic policy (evogym's eval.py, deterministic)."""
    import gymnasium as gym
    from evogym import get_full_connectivity

    env = gym.make("Walker-v0", body=SPEED_BOT, connections=get_full_connectivity(SPEED_BOT))
    obs, _ = env.reset(seed=0)
    total = 0.0
    for _ in range(steps):
        action, _ = model.predict(obs, deterministic=True)
        obs, r, term, trunc, _ = env.step(action)
        total += float(r)
        if term or trunc:
            break
    env.close()
    return total


def curve_callback(evaluate, eval_every: int, curve: list, clock: dict, stop_at: float | None = None):
    """An SB3 callback that, every `eval_every` PPO updates, appends `evaluate(model)` (a return)
    with the timesteps and seconds of learning so far to `curve`; `clock` ({"learn": 0.0, "eval":
    0.0, "updates": 0, "t0": now}) counts learning apart from evaluating. Learning stops once a
    return reaches `stop_at` (None: never). Shared by both sides (bench/rl_learn.py)."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Eval(BaseCallback):
        def _on_rollout_end(self) -> None:
            clock["updates"] += 1

        def _on_rollout_start(self) -> None:
            if clock["updates"] == 0 or clock["updates"] % eval_every:
                return
            clock["learn"] += time.perf_counter() - clock["t0"]
            t = time.perf_counter()
            ret = evaluate(self.model)
            clock["eval"] += time.perf_counter() - t
            curve.append({"timesteps": int(self.model.num_timesteps), "learn_s": clock["learn"],
                          "return": ret})
            print(f"{self.model.num_timesteps:8d} steps  {clock['learn']:7.1f} s learning  return {ret:6.3f}",
                  flush=True)
            clock["t0"] = time.perf_counter()
            if stop_at is not None and ret >= stop_at:
                clock["reached"] = True

        def _on_step(self) -> bool:
            return not clock.get("reached")

    return Eval()


def learn_curve(timesteps: int, eval_every: int, target: float) -> dict:
    """Learn up to `timesteps`, the deterministic return every `eval_every` updates; the clock
    counts learning only."""
    model = example_loop(SPEED_BOT)
    curve: list[dict] = []
    clock = {"learn": 0.0, "t0": time.perf_counter(), "updates": 0, "eval": 0.0}
    model.learn(timesteps, callback=curve_callback(deterministic_return, eval_every, curve, clock))
    clock["learn"] += time.perf_counter() - clock["t0"]
    final = deterministic_return(model)
    curve.append({"timesteps": int(model.num_timesteps), "learn_s": clock["learn"], "return": final})
    reached = next((c for c in curve if c["return"] >= target), None)
    return {"curve": curve, "final_return": final, "learn_s": clock["learn"], "eval_s": clock["eval"],
            "reached": reached}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("learn-speed")
    s.add_argument("--timesteps", type=int, default=4096)
    g = sub.add_parser("ga-loop")
    g.add_argument("--cores", type=int, default=2)
    g.add_argument("--timesteps", type=int, default=2048)
    g.add_argument("--threads", type=int, default=0, help="torch threads per process (0: torch's default)")
    c = sub.add_parser("learn-curve")
    c.add_argument("--timesteps", type=int, default=100_000)
    c.add_argument("--eval-every", type=int, default=8)
    c.add_argument("--target", type=float, default=3.96)
    a = p.parse_args()
    if a.cmd == "learn-speed":
        out = learn_speed(a.timesteps)
    elif a.cmd == "ga-loop":
        out = ga_loop(a.cores, a.timesteps, a.threads or None)
    else:
        out = learn_curve(a.timesteps, a.eval_every, a.target)
    import evogym

    out["evogym"] = getattr(evogym, "__version__", "2.0.0")
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
