"""tasks/sb3_vec_env.py (sgr.rl): an SB3 VecEnv over one batch. Facts checked: it is SB3's VecEnv
with the shapes and dtypes SB3 expects; a finished world's info holds the final observation of the
batched env and the truncation flag, its row the new episode; seeding repeats rollouts and
separates worlds; it steps exactly as gymnasium's single env; mixed bodies; SB3's wrappers and
learners (PPO, A2C, SAC) run on it; evogym's bare ids; and one line without stable-baselines3."""

import sys

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3", reason="the rl extra: pip install 'sgr[rl]'")

from stable_baselines3.common.vec_env import VecEnv, VecMonitor, VecNormalize  # noqa: E402

from sgr.rl import SgrVecEnv, make_vec_env  # noqa: E402
from tasks.env import BatchEnv  # noqa: E402
from tsim.errors import SgrError  # noqa: E402

BODY = np.array([[3, 3, 3, 3, 3], [3, 3, 3, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3]])
SMALL = np.array([[0, 0, 0], [3, 3, 3], [3, 0, 3]])


def _actions(rng: np.random.Generator, n: int, k: int) -> np.ndarray:
    return rng.uniform(0.6, 1.6, (n, k))


def test_it_is_an_sb3_vecenv_with_the_shapes_and_dtypes_sb3_expects():
    env = make_vec_env("sgr/Walker-v0", n_envs=3, seed=0, env_kwargs={"body": BODY})
    assert isinstance(env, VecMonitor) and isinstance(env.unwrapped, VecEnv)
    n_obs, n_act = env.observation_space.shape[0], env.action_space.shape[0]
    assert (n_obs, n_act) == (BatchEnv("Walker-v0", [BODY]).obs_dims[0], int((BODY == 3).sum()))
    obs = env.reset()
    assert obs.shape == (3, n_obs) and obs.dtype == env.observation_space.dtype
    obs, rew, done, infos = env.step(np.ones((3, n_act)))
    assert obs.shape == (3, n_obs) and rew.shape == (3,) and rew.dtype == np.float32
    assert done.shape == (3,) and done.dtype == bool and len(infos) == 3
    assert env.num_envs == 3 and env.get_attr("n_actuators") == [n_act] * 3
    assert "3 robots" in repr(env.unwrapped)


def test_it_steps_exactly_as_gymnasiums_single_env():
    rng = np.random.default_rng(0)
    vec = make_vec_env("sgr/Walker-v0", n_envs=2, env_kwargs={"body": BODY})
    single = gym.make("sgr/Walker-v0", body=BODY)
    obs_v = vec.reset()
    obs_s, _ = single.reset(seed=0)
    assert np.array_equal(obs_v[0], obs_s) and np.array_equal(obs_v[1], obs_s)
    for _ in range(30):
        a = _actions(rng, 1, vec.action_space.shape[0])[0]
        obs_v, r_v, _, _ = vec.step(np.stack([a, a]))
        obs_s, r_s, *_ = single.step(a)
        assert np.array_equal(obs_v[0], obs_s) and np.array_equal(obs_v[1], obs_s)
        assert r_v[0] == np.float32(r_s) and r_v[1] == r_v[0]


def test_a_truncated_episode_reports_its_final_observation_and_restarts_in_the_same_call():
    steps = 12
    vec = make_vec_env("sgr/Walker-v0", n_envs=2, env_kwargs={"body": BODY, "max_episode_steps": steps})
    ref = BatchEnv("Walker-v0", [BODY, BODY], episode_steps=steps)
    first = vec.reset()
    assert np.array_equal(first, ref.reset())
    rng = np.random.default_rng(1)
    for t in range(steps):
        a = _actions(rng, 2, vec.action_space.shape[0])
        obs, _, done, infos = vec.step(a)
        ref_obs, *_ = ref.step(a)
        if t < steps - 1:
            assert not done.any() and not np.array_equal(obs, first)
    assert done.all()
    for i in range(2):
        assert np.array_equal(infos[i]["terminal_observation"], ref_obs[i])
        assert infos[i]["TimeLimit.truncated"] is True
        assert infos[i]["episode"]["l"] == steps  # VecMonitor's episode record
    assert np.array_equal(obs, first)  # the new episode's first observation


def test_a_terminated_episode_is_not_flagged_as_truncated():
    """Robot 0 is moved next to Walker-v0's finish line: it crosses it and terminates; robot 1
    goes on."""
    def near_goal(env: BatchEnv) -> None:
        s = env.sim.state[0, :env.n_points[0]]
        dx, dy = 9.9 - 0.004 - s[:, 0].mean(), 0.1005 - s[:, 1].min()
        for col in (0, 4):
            s[:, col] += dx
            s[:, col + 1] += dy
        s[:, 2] = s[:, 6] = 2.0

    vec = SgrVecEnv("Walker-v0", [BODY, BODY], episode_steps=100)
    ref = BatchEnv("Walker-v0", [BODY, BODY], episode_steps=100)
    vec.reset()
    ref.reset()
    near_goal(vec.batch_env)
    near_goal(ref)
    vec.batch_env.observe()
    ref.observe()
    a = np.ones((2, vec.action_space.shape[0]))
    for _ in range(20):
        obs, _, done, infos = vec.step(a)
        ref_obs, _, term, *_ = ref.step(a)
        if done[0]:
            break
    assert done.tolist() == [True, False] and term[0]
    assert infos[0]["TimeLimit.truncated"] is False
    assert np.array_equal(infos[0]["terminal_observation"], ref_obs[0])
    assert "terminal_observation" not in infos[1]
    assert not np.array_equal(obs[0], ref_obs[0])  # its row is the new episode's


def _rollout(env, seed: int | None, steps: int = 40) -> np.ndarray:
    if seed is not None:
        env.seed(seed)
    rng = np.random.default_rng(5)
    out = [env.reset()]
    for _ in range(steps):  # every world the same actions: worlds differ by their streams alone
        a = _actions(rng, 1, env.action_space.shape[0])
        out.append(env.step(np.repeat(a, env.num_envs, axis=0))[0])
    return np.stack(out)


def test_seeding_repeats_rollouts_and_gives_each_world_its_own_stream():
    """BidirectionalWalker-v0 draws its goals from the task stream: the same seed gives the same
    rollout, world i follows seed + i (as SB3's seed(s) does), another seed another rollout."""
    def env():
        return SgrVecEnv("BidirectionalWalker-v0", [BODY] * 2, episode_steps=60)

    a, b, c = _rollout(env(), 3, 60), _rollout(env(), 3, 60), _rollout(env(), 4, 60)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    assert np.array_equal(a[:, 1], c[:, 0])  # world 1 of seed 3 is world 0 of seed 4
    shifted = make_vec_env("BidirectionalWalker-v0", n_envs=2, seed=3, start_index=1,
                           env_kwargs={"body": BODY, "max_episode_steps": 60}).unwrapped
    assert np.array_equal(_rollout(shifted, None, 60), c)  # SB3's start_index: seed 3 + 1
    assert not np.array_equal(a[:, 0], a[:, 1])


def test_mixed_bodies_share_one_padded_layout():
    vec = make_vec_env("sgr/Walker-v0", n_envs=2, env_kwargs={"bodies": [BODY, SMALL]})
    dims = vec.get_attr("obs_dim")
    acts = vec.get_attr("n_actuators")
    assert acts == [int((BODY == 3).sum()), int((SMALL == 3).sum())] and dims[0] > dims[1]
    obs = vec.reset()
    assert obs.shape == (2, dims[0]) and not obs[1, dims[1]:].any()
    assert np.array_equal(vec.get_attr("body", [1])[0], SMALL)
    pts = vec.env_method("robot_points", indices=[1])[0]
    assert pts.shape[0] == 2


def test_sb3_learners_and_wrappers_run_on_it():
    from stable_baselines3 import A2C, PPO, SAC

    env = VecNormalize(make_vec_env("sgr/Walker-v0", n_envs=4, seed=0, env_kwargs={"body": BODY}))
    ppo = PPO("MlpPolicy", env, n_steps=32, batch_size=64, n_epochs=2, seed=0, device="cpu")
    ppo.learn(256)
    assert ppo.num_timesteps >= 256
    env.training = False
    obs = env.reset()
    action, _ = ppo.predict(obs, deterministic=True)
    assert action.shape == (4, env.action_space.shape[0])
    a2c = A2C("MlpPolicy", make_vec_env("sgr/Walker-v0", n_envs=4, env_kwargs={"body": BODY}),
              n_steps=8, seed=0, device="cpu")
    a2c.learn(64)
    sac = SAC("MlpPolicy", make_vec_env("sgr/Walker-v0", n_envs=2, env_kwargs={"body": BODY}),
              learning_starts=16, batch_size=16, buffer_size=500, seed=0, device="cpu")
    sac.learn(48)
    assert a2c.num_timesteps >= 64 and sac.num_timesteps >= 48


def test_ppo_learns_the_same_run_twice():
    """Same seeds, same simulator: two PPO runs give the same policy to the last bit."""
    from stable_baselines3 import PPO

    def train():
        env = make_vec_env("sgr/Walker-v0", n_envs=4, seed=0, env_kwargs={"body": BODY})
        model = PPO("MlpPolicy", env, n_steps=16, batch_size=32, n_epochs=1, seed=0, device="cpu")
        model.learn(64)
        return np.concatenate([p.detach().numpy().ravel() for p in model.policy.parameters()])

    assert np.array_equal(train(), train())


def test_evogym_bare_ids_take_evogyms_episode_length():
    import sgr.evogym.envs  # noqa: F401  (registers the bare ids)
    from tasks.specs import TASKS

    vec = make_vec_env("Walker-v0", n_envs=1, env_kwargs={"body": BODY})
    assert vec.unwrapped.batch_env.episode_steps == TASKS["Walker-v0"].evogym_steps


@pytest.mark.parametrize("kwargs, words", [
    ({"env_id": "sgr/Nope-v0", "env_kwargs": {"body": BODY}}, "unknown env id 'sgr/Nope-v0'"),
    ({"env_id": "sgr/Walker-v0", "env_kwargs": {}}, "env_kwargs needs body="),
    ({"env_id": "sgr/Walker-v0", "n_envs": 3, "env_kwargs": {"bodies": [BODY, BODY]}},
     "2 bodies for n_envs=3"),
    ({"env_id": "sgr/Walker-v0", "env_kwargs": {"body": BODY, "colour": 1}}, "unknown key 'colour'"),
    ({"env_id": "sgr/Walker-v0", "env_kwargs": {"bodies": [BODY], "connections": np.zeros((2, 0))}},
     "connections goes with body="),
    ({"env_id": "sgr/Walker-v0", "env_kwargs": {"body": BODY, "render_mode": "human"}},
     "render_mode 'human' is not supported here"),
    ({"env_id": "sgr/Walker-v0", "env_kwargs": {"body": BODY}, "wrapper_class": gym.wrappers.ClipAction},
     "wrapper_class: the robots are one batched VecEnv"),
])
def test_bad_arguments_are_one_line(kwargs, words):
    with pytest.raises(SgrError, match=words):
        make_vec_env(**kwargs)


def test_without_stable_baselines3_it_says_what_to_install(monkeypatch):
    import tasks.sb3_vec_env as module

    monkeypatch.setattr(module, "_CLASS", None)
    monkeypatch.setitem(sys.modules, "stable_baselines3", None)
    monkeypatch.setitem(sys.modules, "stable_baselines3.common.vec_env", None)
    with pytest.raises(SgrError, match=r"needs stable-baselines3 and torch: pip install 'sgr\[rl\]'"):
        make_vec_env("sgr/Walker-v0", env_kwargs={"body": BODY})


def test_rgb_array_rendering_gives_each_robots_picture_and_sb3_tiles_them():
    vec = make_vec_env("sgr/Walker-v0", n_envs=2,
                       env_kwargs={"bodies": [BODY, SMALL], "render_mode": "rgb_array"})
    assert vec.render_mode == "rgb_array"
    vec.reset()
    images = vec.get_images()
    assert len(images) == 2 and all(im.ndim == 3 and im.shape[2] == 3 and im.dtype == np.uint8
                                    for im in images)
    assert not np.array_equal(images[0], images[1])  # two bodies, two pictures
    tiled = vec.render()  # SB3's own grid of them
    h, w, _ = images[0].shape
    assert tiled.ndim == 3 and tiled.shape[0] * tiled.shape[1] >= 2 * h * w
    assert any(np.array_equal(tiled[r:r + h, c:c + w], images[1]) for r in range(0, tiled.shape[0], h)
               for c in range(0, tiled.shape[1], w))
