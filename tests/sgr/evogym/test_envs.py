"""`import sgr.evogym.envs` registers evogym's 32 tasks under their bare ids with evogym's episode
lengths and keyword arguments (tests/data/evogym_api/registry.json, read from evogym's registry),
and `gym.make` of a bare id earns evogym's rewards (tests/data/evogym32, recorded from evogym)."""

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import sgr.evogym.envs  # noqa: F401  (registers the bare ids)
from sgr.evogym import BASELINE_ENV_NAMES, get_full_connectivity
from sgr.evogym.envs import TaskEnv, TaskVectorEnv

DATA = Path(__file__).resolve().parents[2] / "data"
REGISTRY = json.loads((DATA / "evogym_api" / "registry.json").read_text())
BODY = np.array([[3, 3, 3], [3, 0, 3]])


def test_every_bare_id_is_registered_with_evogyms_episode_length():
    assert list(REGISTRY) == BASELINE_ENV_NAMES
    for name, ref in REGISTRY.items():
        assert gym.spec(name).max_episode_steps == ref["max_episode_steps"], name
        assert ref["kwargs"] == ["body", "connections", "render_mode", "render_options"]


def test_evogyms_env_classes_are_importable_by_name_and_bound_to_their_task():
    for name, ref in REGISTRY.items():
        cls = getattr(sgr.evogym.envs, ref["class"])
        assert cls.TASK == name and issubclass(cls, TaskEnv)
    env = sgr.evogym.envs.Climb2(BODY, render_mode="img")
    assert env.task == "Climber-v2" and env.render().shape == (600, 1200, 3)


@pytest.mark.slow
@pytest.mark.parametrize("task", ["Walker-v0", "Pusher-v0", "Thrower-v0", "Climber-v1", "Traverser-v0"])
def test_gym_make_of_a_bare_id_earns_evogyms_rewards(task):
    d = np.load(DATA / "evogym32" / f"returns_{task}.npz", allow_pickle=False)
    for case in range(2):
        env = gym.make(task, body=d["body"][case])
        obs, _ = env.reset()
        n = int(d["obs_dim"][case])
        assert np.abs(obs - d["obs0"][case, :n]).max() < 1e-9
        steps = int(d["steps_run"][case])
        rewards = [env.step(d["actions"][case, t, :d["n_act"][case]])[1] for t in range(steps)]
        assert np.abs(np.array(rewards) - d["rewards"][case, :steps]).max() < 1e-9, (task, case)


def test_connections_kwarg_builds_that_topology():
    full = gym.make("Walker-v0", body=BODY, connections=get_full_connectivity(BODY))
    default = gym.make("Walker-v0", body=BODY)
    a = np.full(5, 1.4)
    np.testing.assert_array_equal(full.reset()[0], default.reset()[0])
    np.testing.assert_array_equal(full.step(a)[0], default.step(a)[0])
    cut = get_full_connectivity(BODY)[:, 1:]  # cells 0 and 1 no longer glued: 2 more points
    loose = gym.make("Walker-v0", body=BODY, connections=cut)
    assert loose.observation_space.shape[0] == default.observation_space.shape[0] + 4


def test_render_modes():
    plain = gym.make("Walker-v0", body=BODY)
    plain.reset()
    assert plain.render() is None
    for mode in ("img", "rgb_array"):
        env = gym.make("Walker-v0", body=BODY, render_mode=mode,
                       render_options={"hide_grid": True, "hide_background": True})
        env.reset()
        img = env.render()
        assert img.dtype == np.uint8 and img.shape == (600, 1200, 3)
        assert (img == 255).all(axis=2).mean() > 0.5  # white background, no grid
    with pytest.raises(ValueError, match="render_mode 'movie' is not one of"):
        gym.make("Walker-v0", body=BODY, render_mode="movie")


def test_bad_input_to_a_bare_id_is_one_clear_error():
    with pytest.raises(ValueError, match="need a body="):
        gym.make("Walker-v0")
    env = gym.make("Walker-v0", body=BODY)
    env.reset()
    with pytest.raises(ValueError, match=r"wrong action shape: expected \(5,\), got \(4,\)"):
        env.step(np.ones(4))


def test_make_vec_of_a_bare_id_is_the_batched_env_and_steps_as_single_envs():
    vec = gym.make_vec("Walker-v0", num_envs=3, body=BODY)
    assert isinstance(vec, TaskVectorEnv)
    single = gym.make("Walker-v0", body=BODY)
    assert isinstance(single.unwrapped, TaskEnv)
    obs, _ = vec.reset()
    s_obs, _ = single.reset()
    a = np.full((3, 5), 1.3)
    for _ in range(5):
        obs, rew, *_ = vec.step(a)
        s_obs, s_rew, *_ = single.step(a[0])
    np.testing.assert_array_equal(obs[1], s_obs)
    assert rew[2] == s_rew
