"""Learning, not just stepping: wall time until PPO's deterministic policy for evogym's speed_bot
on Walker-v0 reaches a return (default 3.96, what evogym's example loop reaches after 100,000
timesteps), with `sgr.rl.make_vec_env` and N envs in one batch.

Every `--eval-every` PPO updates the deterministic policy plays one episode of evogym's length
(500 steps) in a one-env batch, as evogym's `examples/ppo/eval.py` does; the clock counts learning
only (evaluation time is printed apart). The curve (timesteps, learning seconds, return) is
printed; `--record` writes it as a record (tasks/records.py: the seconds and timesteps to the
target, the curve) and `--plot` draws it, return against seconds of learning.

    python bench/rl_learn.py                                 # the recipe's defaults, 32 envs
    python bench/rl_learn.py --envs 16 --lr 2.5e-4 --epochs 4 --no-normalize   # evogym's settings
    python bench/rl_learn.py --record docs/records/rl-learning.json --plot docs/img/rl-learning.png
    python bench/rl_learn.py --evogym-python ~/evogym-venv/bin/python ...   # and evogym's own loop

With `--evogym-python` (a venv with evogym 2.0 and SB3) evogym's example loop is run in evogym
itself first, 100,000 timesteps with the deterministic return every 8 updates
(bench/evogym_side.py), on its own: the record and the picture then hold both curves.

Needs the rl extra: pip install 'sgr[rl]'.
"""

from __future__ import annotations

import argparse
import sys
import time
from functools import partial
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.evogym_side import curve_callback  # noqa: E402
from bench.rl_bench import SPEED_BOT  # noqa: E402

# the recipe's defaults for many envs (docs/RL.md, "A recipe that learns sooner")
# (measured here, seeds 0 and 1: 30-39 s of learning, 45-53k timesteps; 64 envs, batch 1024, 8 epochs:
# 88 s, 197k timesteps; evogym's loop needs 100k timesteps)
RECIPE = {"envs": 32, "n_steps": 64, "batch": 512, "epochs": 10, "lr": 1e-3, "normalize": True,
          "clip": 0.2, "ent": 0.0, "gamma": 0.99}


def deterministic_return(model, norm, steps: int = 500) -> float:
    """One episode of the deterministic policy in a one-env batch (observations normalised with
    the learner's statistics, frozen)."""
    from sgr.rl import SgrVecEnv

    env = SgrVecEnv("Walker-v0", [SPEED_BOT], episode_steps=steps)
    obs = env.reset()
    total = 0.0
    for _ in range(steps):
        o = norm.normalize_obs(obs) if norm is not None else obs
        action, _ = model.predict(o, deterministic=True)
        obs, r, done, _ = env.step(action)
        total += float(r[0])
        if done[0]:
            break
    return total


def learn(a: argparse.Namespace) -> list[dict]:
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from sgr.rl import make_vec_env

    torch.manual_seed(a.seed)
    env = make_vec_env("Walker-v0", n_envs=a.envs, seed=a.seed, env_kwargs={"body": SPEED_BOT})
    norm = VecNormalize(env, norm_obs=True, norm_reward=True, gamma=a.gamma) if a.normalize else None
    model = PPO("MlpPolicy", norm or env, n_steps=a.n_steps, batch_size=a.batch, n_epochs=a.epochs,
                learning_rate=a.lr, gamma=a.gamma, gae_lambda=0.95, clip_range=a.clip, ent_coef=a.ent,
                vf_coef=0.5, max_grad_norm=0.5, seed=a.seed, device="cpu", verbose=0)
    curve: list[dict] = []
    clock = {"learn": 0.0, "eval": 0.0, "t0": time.perf_counter(), "updates": 0}
    evaluate = partial(deterministic_return, norm=norm)
    model.learn(a.timesteps, callback=curve_callback(evaluate, a.eval_every, curve, clock, stop_at=a.target))
    reached = next((c for c in curve if c["return"] >= a.target), None)
    said = f"{reached['learn_s']:.1f} s of learning, {reached['timesteps']} timesteps" if reached else "no"
    print(f"# reached {a.target}: {said}; evaluation {clock['eval']:.1f} s")
    return curve


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--envs", type=int, default=RECIPE["envs"])
    p.add_argument("--n-steps", type=int, default=RECIPE["n_steps"])
    p.add_argument("--batch", type=int, default=RECIPE["batch"])
    p.add_argument("--epochs", type=int, default=RECIPE["epochs"])
    p.add_argument("--lr", type=float, default=RECIPE["lr"])
    p.add_argument("--clip", type=float, default=RECIPE["clip"])
    p.add_argument("--ent", type=float, default=RECIPE["ent"])
    p.add_argument("--gamma", type=float, default=RECIPE["gamma"])
    p.add_argument("--no-normalize", dest="normalize", action="store_false")
    p.add_argument("--target", type=float, default=3.96)
    p.add_argument("--timesteps", type=int, default=1_000_000, help="the most to learn")
    p.add_argument("--eval-every", type=int, default=2, help="PPO updates between evaluations")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--record", help="write the figures and the curve as a record here")
    p.add_argument("--plot", help="draw the curve here (PNG)")
    p.add_argument("--evogym-python", help="the Python of a venv with evogym 2.0 and SB3: evogym's example "
                                           "loop's curve too")
    p.add_argument("--evogym-timesteps", type=int, default=100_000)
    a = p.parse_args(argv)
    from tasks.records import cpu_model

    print(f"# {cpu_model()}; {vars(a)}")
    evogym = None
    if a.evogym_python:
        from bench.evogym_side import run_side

        evogym = run_side(a.evogym_python, "learn-curve", "--timesteps", str(a.evogym_timesteps),
                          "--target", str(a.target))
        hit = evogym["reached"]
        print(f"# evogym's loop in evogym {evogym['evogym']}: final return {evogym['final_return']:.3f} "
              "after "
              f"{evogym['learn_s']:.1f} s of learning; reached {a.target}: "
              + (f"{hit['learn_s']:.1f} s, {hit['timesteps']} timesteps" if hit else "no"), flush=True)
    curve = learn(a)
    reached = next((c for c in curve if c["return"] >= a.target), None)
    if a.record:
        from tasks.records import figure, write_record

        figures = {"final_return": figure(curve[-1]["return"] if curve else float("nan"), "return")}
        if reached:
            figures.update(learn_s_to_target=figure(reached["learn_s"], "s"),
                           timesteps_to_target=figure(reached["timesteps"], "timesteps"))
        if evogym:
            figures["evogym_final_return"] = figure(evogym["final_return"], "return")
            figures["evogym_learn_s"] = figure(evogym["learn_s"], "s")
            if evogym["reached"]:
                figures["evogym_learn_s_to_target"] = figure(evogym["reached"]["learn_s"], "s")
                figures["evogym_timesteps_to_target"] = figure(evogym["reached"]["timesteps"], "timesteps")
                if reached:
                    ratio = evogym["reached"]["learn_s"] / reached["learn_s"]
                    figures["sooner_than_evogym"] = figure(ratio, "x")
        write_record(a.record, None, figures, settings=vars(a), curve=curve, evogym=evogym)
        print(f"wrote {a.record}")
    if a.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 3.5), dpi=100)
        ax.plot([c["learn_s"] for c in curve], [c["return"] for c in curve], marker=".",
                label=f"sgr.rl, {a.envs} envs in one batch")
        if evogym:
            ax.plot([c["learn_s"] for c in evogym["curve"]], [c["return"] for c in evogym["curve"]],
                    marker=".", label="evogym's example loop in evogym (1 env)")
            ax.set_xscale("log")
        ax.axhline(a.target, color="grey", ls="--", lw=1, label=f"target {a.target}")
        ax.set_xlabel("seconds of learning")
        ax.set_ylabel("deterministic return")
        ax.legend(loc="upper left")
        fig.tight_layout()
        fig.savefig(a.plot)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
