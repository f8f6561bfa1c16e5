"""PPO learn steps per second through stable-baselines3: evogym's example loop (one env through
SB3's make_vec_env, batch 4) on `sgr.evogym`, against `sgr.rl.make_vec_env` with N envs in one
batch (batch n_steps x N / 4), with evogym's other PPO arguments (examples/ppo/args.py: learning
rate 2.5e-4, n_steps 128, 4 epochs, gamma 0.99, GAE 0.95, clip 0.1, entropy 0.01, vf 0.5, grad
norm 0.5), on Walker-v0 with evogym's speed_bot body.

Each line: envs, timesteps learned, seconds (after a warm-up: the simulator's kernels compile at
their first launch), learn steps/s, and the share of the time spent stepping the environment
(the rest is SB3: the policy's forward passes, the rollout buffer and the updates), which says
what limits the figure.

    python bench/rl_bench.py                       # 1, 16, 64, 256 envs
    python bench/rl_bench.py --envs 64 --timesteps 65536
    python bench/rl_bench.py --record docs/records/rl-ppo-speed.json   # (a clean tree's commit in it)

Needs the rl extra: pip install 'sgr[rl]'.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

# evogym's examples/world_data/speed_bot.json, as a voxel matrix (row 0 the top)
SPEED_BOT = np.array([[2, 3, 3, 3, 1], [1, 3, 3, 3, 1], [3, 1, 0, 1, 3], [3, 0, 0, 0, 3]])
EVOGYM_PPO = dict(learning_rate=2.5e-4, n_steps=128, n_epochs=4, gamma=0.99, gae_lambda=0.95,
                  clip_range=0.1, ent_coef=0.01, vf_coef=0.5, max_grad_norm=0.5)


class StepClock:
    """Wraps a VecEnv's step_wait and reset to add up the seconds spent in them."""

    def __init__(self, env):
        self.seconds = 0.0
        for name in ("step_wait", "reset"):
            inner = getattr(env, name)

            def timed(*a, _inner=inner, **k):
                t0 = time.perf_counter()
                try:
                    return _inner(*a, **k)
                finally:
                    self.seconds += time.perf_counter() - t0
            setattr(env, name, timed)


def evogym_loop_env():
    """evogym's run_ppo loop: SB3's own make_vec_env over gymnasium's bare id, one env."""
    from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env

    import sgr.evogym.envs  # noqa: F401  (the bare ids, evogym's episode length)
    from sgr.evogym.utils import get_full_connectivity

    return sb3_make_vec_env("Walker-v0", n_envs=1, seed=0,
                            env_kwargs={"body": SPEED_BOT, "connections": get_full_connectivity(SPEED_BOT)})


def measure(n_envs: int, timesteps: int) -> dict:
    """One PPO learn of `timesteps` on `n_envs` envs; its seconds and the env's share."""
    from stable_baselines3 import PPO

    from sgr.rl import make_vec_env
    if n_envs == 1:
        env, batch, what = evogym_loop_env(), 4, "evogym's loop (SB3 make_vec_env, 1 env) on sgr.evogym"
    else:
        env = make_vec_env("Walker-v0", n_envs=n_envs, seed=0, env_kwargs={"body": SPEED_BOT})
        batch, what = EVOGYM_PPO["n_steps"] * n_envs // 4, "sgr.rl.make_vec_env"
    env.reset()  # warm: Taichi compiles the simulator's kernels at their first launch, not measured here
    for _ in range(3):
        env.step(np.stack([env.action_space.sample() for _ in range(n_envs)]))
    clock = StepClock(env.unwrapped if n_envs > 1 else env)
    model = PPO("MlpPolicy", env, batch_size=batch, seed=0, device="cpu", verbose=0, **EVOGYM_PPO)
    t0 = time.perf_counter()
    model.learn(timesteps)
    wall = time.perf_counter() - t0
    done = model.num_timesteps
    return {"what": what, "envs": n_envs, "batch": batch, "timesteps": int(done), "seconds": wall,
            "steps_per_s": done / wall, "env_share": clock.seconds / wall}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--envs", type=int, nargs="+", default=[1, 16, 64, 256])
    p.add_argument("--timesteps", type=int, default=0,
                   help="per measurement (default: four PPO rollouts, 4 x 128 x N; 4096 for 1 env)")
    p.add_argument("--record", help="write the figures as JSON here")
    p.add_argument("--evogym-python", help="the Python of a venv with evogym 2.0 and SB3: also time evogym's "
                                           "example loop in evogym itself (bench/evogym_side.py)")
    a = p.parse_args(argv)
    from tasks.records import cpu_model

    rows = []
    print(f"# {cpu_model()}; Walker-v0, speed_bot, evogym's PPO arguments")
    evogym = None
    if a.evogym_python:
        from bench.evogym_side import run_side

        evogym = run_side(a.evogym_python, "learn-speed", "--timesteps", str(a.timesteps or 4096))
        print(f"   evogym's loop in evogym {evogym['evogym']}: {evogym['timesteps']:7d} steps  "
              f"{evogym['seconds']:7.1f} s  {evogym['steps_per_s']:8.0f} learn steps/s", flush=True)
    for n in a.envs:
        steps = a.timesteps or (4096 if n == 1 else 4 * EVOGYM_PPO["n_steps"] * n)
        r = measure(n, steps)
        rows.append(r)
        print(f"{n:4d} envs  batch {r['batch']:5d}  {r['timesteps']:7d} steps  {r['seconds']:7.1f} s  "
              f"{r['steps_per_s']:8.0f} learn steps/s  env {100 * r['env_share']:4.1f} %  ({r['what']})",
              flush=True)
    if evogym:
        print("vs evogym's loop in evogym: " + ", ".join(
            f"{r['envs']} envs {r['steps_per_s'] / evogym['steps_per_s']:.1f}x" for r in rows))
    base = next((r["steps_per_s"] for r in rows if r["envs"] == 1), None)
    if base:
        print("vs evogym's loop on sgr.evogym: " + ", ".join(
            f"{r['envs']} envs {r['steps_per_s'] / base:.1f}x" for r in rows if r["envs"] > 1))
    if a.record:
        from tasks.records import figure, write_record

        figures = {f"ppo_learn_steps_per_s_{r['envs']}_envs": figure(r["steps_per_s"], "steps/s")
                   for r in rows}
        figures.update({f"env_share_{r['envs']}_envs": figure(r["env_share"], "fraction") for r in rows})
        if evogym:
            figures["ppo_learn_steps_per_s_evogym"] = figure(evogym["steps_per_s"], "steps/s")
            figures.update({f"vs_evogym_{r['envs']}_envs":
                            figure(r["steps_per_s"] / evogym["steps_per_s"], "x") for r in rows})
        write_record(a.record, None, figures, rows=rows, evogym=evogym)
        print(f"wrote {a.record}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
