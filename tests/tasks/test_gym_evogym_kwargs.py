"""The `sgr/<task>` ids take evogym's keyword arguments: `connections` (the body's glue) and
`render_mode` 'rgb_array' / 'img' with `render_options`; other modes are one clear error."""

import gymnasium as gym
import numpy as np
import pytest

import tasks  # registers sgr/<task>

BODY = np.array([[3, 3, 3], [3, 0, 3]])
FULL = np.array([[0, 1, 0, 2], [1, 2, 3, 5]])  # every adjacent pair of BODY's voxels


def test_connections_glue_the_body_as_given():
    full = gym.make("sgr/Walker-v0", body=BODY, connections=FULL)
    default = gym.make("sgr/Walker-v0", body=BODY)
    np.testing.assert_array_equal(full.reset()[0], default.reset()[0])
    loose = gym.make("sgr/Walker-v0", body=BODY, connections=FULL[:, 1:])  # cells 0, 1 unglued
    assert loose.observation_space.shape[0] == default.observation_space.shape[0] + 4
    vec = gym.make_vec("sgr/Walker-v0", num_envs=2, body=BODY, connections=FULL[:, 1:])
    assert vec.single_observation_space.shape == loose.observation_space.shape


def test_rgb_array_renders_and_no_mode_renders_nothing():
    env = gym.make("sgr/Thrower-v0", body=BODY, render_mode="rgb_array", render_options={"hide_grid": True})
    env.reset()
    img = env.render()
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    plain = gym.make("sgr/Walker-v0", body=BODY)
    plain.reset()
    assert plain.render() is None
    with pytest.raises(ValueError, match="render_mode 'screen' is not supported here"):
        tasks.SgrEnv("Walker-v0", BODY, render_mode="screen")
    # 'human' through gym.make is gymnasium's HumanRendering around our 'rgb_array'
    assert gym.make("sgr/Walker-v0", body=BODY, render_mode="human").unwrapped.render_mode == "rgb_array"
