"""Batched PPO (evolve/rollout/ppo.py): evogym's PPO arguments as defaults, one line for a bad
setting, the same weights from the same seed, and a policy that learns to walk."""

from __future__ import annotations

import numpy as np
import pytest

from evolve.nn.mlp import mlp_policy
from evolve.rollout.episodes import rollout_policy
from evolve.rollout.ppo import PpoSettings, train_bodies
from tsim.errors import SgrError

pytest.importorskip("torch", reason="PPO needs torch: pip install 'sgr[rl]'")

# evogym's examples/world_data/speed_bot.json, as a voxel matrix (row 0 the top)
SPEED_BOT = np.array([[2, 3, 3, 3, 1], [1, 3, 3, 3, 1], [3, 1, 0, 1, 3], [3, 0, 0, 0, 3]])
OTHER = np.array([[3, 3, 3], [1, 0, 1], [4, 0, 4]])


def test_defaults_are_evogyms_ppo_arguments():
    """evogym 2.0's examples/ppo/args.py, argument by argument."""
    s = PpoSettings()
    assert (s.learning_rate, s.n_steps, s.batch_size, s.n_epochs, s.gamma, s.gae_lambda, s.vf_coef,
            s.max_grad_norm, s.ent_coef, s.clip_range, s.timesteps, s.n_envs) == \
        (2.5e-4, 128, 4, 4, 0.99, 0.95, 0.5, 0.5, 0.01, 0.1, 1_000_000, 1)
    assert PpoSettings.from_config({}) == s and PpoSettings.from_config(s.to_json()) == s


@pytest.mark.parametrize(("raw", "match"), [
    ({"n_step": 64}, "unknown key 'n_step'; known keys: timesteps, n_envs"),
    ({"n_steps": 0}, "ppo.n_steps' must be an int from 1"),
    ({"learning_rate": "fast"}, "ppo.learning_rate' must be a number"),
    ({"gamma": 1.5}, "ppo.gamma' must be at most 1"),
    ({"batch_size": 512, "n_steps": 128}, "batch_size' .512. must be at most n_steps x n_envs .128."),
    ({"hidden": [64, 0]}, "ppo.hidden' must be a list of layer widths"),
    ([1, 2], "key 'ppo' must be a mapping"),
])
def test_a_bad_setting_is_one_line_naming_the_key(raw, match):
    with pytest.raises(SgrError, match=match) as info:
        PpoSettings.from_config(raw, "run.yaml")
    assert "\n" not in str(info.value) and str(info.value).startswith("run.yaml: key 'ppo")


def weights(trained) -> list[np.ndarray]:
    return [w for t in trained for w in (*t.controller.weights, *t.controller.biases)]


def test_the_same_seed_trains_the_same_weights_to_the_bit():
    s = PpoSettings(timesteps=256, n_envs=2, n_steps=32, batch_size=16, n_epochs=2)
    a = train_bodies("Walker-v0", [SPEED_BOT, OTHER], s, seed=5, episode_steps=40)
    b = train_bodies("Walker-v0", [SPEED_BOT, OTHER], s, seed=5, episode_steps=40)
    c = train_bodies("Walker-v0", [SPEED_BOT, OTHER], s, seed=6, episode_steps=40)
    assert all(np.array_equal(x, y) for x, y in zip(weights(a), weights(b), strict=True))
    assert not all(np.array_equal(x, y) for x, y in zip(weights(a), weights(c), strict=True))
    assert [t.timesteps for t in a] == [256, 256]
    assert all(t.episodes == 6 for t in a)  # 2 envs x 3 episodes of 40 steps
    assert (a[0].controller.input_size, a[0].controller.n_actions) == (2 + 2 * 28, 10)  # speed_bot: 28 points


@pytest.mark.slow
def test_ppo_teaches_the_speed_bot_to_walk():
    """20,480 timesteps on 8 envs (batch 128, lr 1e-3): the deterministic policy walks (evogym's
    500-step Walker-v0 episode; the untrained policy's mean action, 0.6 everywhere, scores ~0)."""
    s = PpoSettings(timesteps=20_480, n_envs=8, n_steps=64, batch_size=128, learning_rate=1e-3)
    trained = train_bodies("Walker-v0", [SPEED_BOT], s, seed=0, episode_steps="evogym")
    ctrl = trained[0].controller
    walked = rollout_policy("Walker-v0", [SPEED_BOT], lambda env: mlp_policy(env, [ctrl]), "evogym")[0]

    class Still:
        def act(self, obs):
            return np.full((1, 10), 0.6)

    still = rollout_policy("Walker-v0", [SPEED_BOT], lambda env: Still(), "evogym")[0]
    assert abs(still) < 0.1 and walked > 0.5, (still, walked)
