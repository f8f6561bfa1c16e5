"""gymnasium adapters: registration, check_env, evogym's spaces, point read-out, the VectorEnv."""

import json

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tasks  # noqa: F401 - registers the sgr/ ids
from tasks.env import BatchEnv, obs_dim
from tasks.specs import TASKS

BODY = np.array([[3, 3, 3, 3, 3], [3, 3, 3, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3]])


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("task", list(TASKS))
def test_check_env_passes_with_evogym_spaces(task):
    env = gym.make(f"sgr/{task}", body=BODY)
    check_env(env.unwrapped, skip_render_check=True)
    n_points = env.unwrapped.robot_points().shape[1]
    assert env.observation_space.shape == (obs_dim(task, n_points),)
    assert (env.observation_space.low[0], env.observation_space.high[0]) == (-100.0, 100.0)
    assert env.action_space.shape == (22,)  # BODY has 22 actuators
    assert (env.action_space.low[0], env.action_space.high[0]) == (0.6, 1.6)
    assert env.spec.max_episode_steps == TASKS[task].paper_steps


@pytest.mark.parametrize("env_id", ["sgr/Carrier-v0", "sgr/Walker-v0", "Carrier-v0", "BridgeWalker-v0"])
def test_a_task_whose_name_has_a_later_version_is_made_without_an_out_of_date_warning(env_id):
    """Carrier-v0 and Carrier-v1 are two tasks, not two versions of one: gymnasium must not warn
    that sgr/Carrier-v0 "is out of date" and suggest v1 (sgr ids and sgr.evogym's bare ids)."""
    import warnings

    import sgr.evogym.envs  # noqa: F401 - registers the bare ids

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = gym.make(env_id, body=BODY)
        env.reset(seed=0)
    assert not [w for w in caught if "out of date" in str(w.message)], [str(w.message) for w in caught]
    assert env.spec.id == env_id


def test_time_limit_truncates_at_the_paper_length_and_is_overridable():
    env = gym.make("sgr/Thrower-v0", body=BODY, max_episode_steps=5)
    env.reset(seed=0)
    for _ in range(4):
        assert not env.step(np.ones(22))[3]
    assert env.step(np.ones(22))[3]


@pytest.mark.parametrize("case", ["case12_thrower_walker_sq30h15col1",
                                  "case14_thrower_sample1006_sin20col1",
                                  "case15_thrower_sample1001_sin40col1"])
def test_robot_and_box_points_follow_evogym_point_order(data_dir, case):
    """At reset the robot's and the package's points equal, point for point, the positions evogym's
    C++ simulator held (`world_pos0`, evogym's global order); the reset observation equals evogym's."""
    z = np.load(data_dir / "traces" / f"{case}.npz", allow_pickle=False)
    where = {o["name"]: o for o in json.loads(str(z["world_objects"]))}

    def evogym_points(name):
        o = where[name]
        return z["world_pos0"][:, o["first_point"]:o["first_point"] + o["n_points"]]

    env = gym.make("sgr/Thrower-v0", body=z["body"]).unwrapped
    obs, _ = env.reset(seed=0)
    assert where["package"]["n_points"] == 12
    assert np.array_equal(env.robot_points(), evogym_points("robot"))
    assert np.array_equal(env.object_points("package"), evogym_points("package"))
    # evogym's env rescales positions (/0.1, *0.1): 1 ulp differences
    assert obs.shape == z["obs"][0].shape
    assert np.abs(obs - z["obs"][0]).max() <= 1e-15


def test_wrong_action_shape_names_the_problem():
    env = gym.make("sgr/Walker-v0", body=BODY).unwrapped
    env.reset()
    with pytest.raises(ValueError, match="wrong action shape"):
        env.step(np.ones(21))
    with pytest.raises(ValueError, match="non-finite"):
        env.step(np.full(22, np.nan))


def test_vector_env_matches_batch_env_and_autoresets_finished_robots():
    small = np.array([[0, 0, 0], [2, 3, 2], [4, 0, 4]])
    vec = gym.make_vec("sgr/Walker-v0", bodies=[BODY, small], max_episode_steps=4)
    ref = BatchEnv("Walker-v0", [BODY, small], episode_steps=4)
    obs, _ = vec.reset(seed=1)
    assert np.array_equal(obs, ref.reset())
    assert vec.single_action_space.shape == (22,) and vec.action_space.shape == (2, 22)
    acts = np.full((2, 22), 1.3)
    for _ in range(3):
        o, r, term, trunc, _ = vec.step(acts)
        o2, r2, *_ = ref.step(acts)
        assert np.array_equal(o, o2) and np.array_equal(r, r2) and not trunc.any()
    o, r, term, trunc, info = vec.step(acts)
    o2, *_ = ref.step(acts)
    assert trunc.all() and np.array_equal(info["final_obs"], o2)
    assert np.array_equal(o, ref.reset())  # same-step autoreset returns the reset observation
