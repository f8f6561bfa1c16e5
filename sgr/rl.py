"""Reinforcement learning on sgr's batched simulator with stable-baselines3 (docs/RL.md).

    from stable_baselines3 import PPO
    from sgr.rl import make_vec_env
    env = make_vec_env("sgr/Walker-v0", n_envs=64, seed=0, env_kwargs={"body": body})
    PPO("MlpPolicy", env, n_steps=128, batch_size=2048).learn(200_000)

`make_vec_env` has SB3's signature; its `VecEnv` (`SgrVecEnv`) steps all n_envs robots in one
batched simulation (tasks/sb3_vec_env.py). Needs the extra: pip install 'sgr[rl]'.
"""

from __future__ import annotations

from tasks.sb3_vec_env import INSTALL, RobotView, SgrVecEnv, make_vec_env, task_of

__all__ = ["INSTALL", "RobotView", "SgrVecEnv", "make_vec_env", "task_of"]
