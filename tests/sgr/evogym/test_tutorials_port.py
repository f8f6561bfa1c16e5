"""evogym's tutorials run on sgr.evogym with only their imports changed (`evogym` -> `sgr.evogym`;
the files in evogym_tutorials/ are evogym's tutorials/basic_api.py, rendering_options.py,
envs/__init__.py and envs/simple_env.py, github.com/EvolutionGym/evogym, MIT licence), headless.

The tutorial env (envs/simple_env.py over world_data/simple_walker_env.json) gives evogym's
observations and rewards over a whole 500-step episode (tests/data/evogym_api/simple_env.npz,
recorded from evogym by references/evogym_api_reference.py)."""

import importlib.util
import runpy
import shutil
import sys
import types
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
TUTORIALS = HERE / "evogym_tutorials"
ROOT = HERE.parents[2]
DATA = ROOT / "tests" / "data" / "evogym_api"


@pytest.fixture
def tutorial_dir(tmp_path, monkeypatch):
    """A copy of the tutorials folder layout: the scripts read world_data/ from the working dir."""
    (tmp_path / "world_data").mkdir()
    for f in ("simple_environment.json", "simple_walker_env.json", "simple_environment_with_robot.json"):
        shutil.copy(DATA / f, tmp_path / "world_data" / f)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(TUTORIALS))
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    yield tmp_path
    for name in [m for m in sys.modules if m == "envs" or m.startswith("envs.")]:
        del sys.modules[name]


def _actions():
    spec = importlib.util.spec_from_file_location("evogym_api_reference",
                                                  ROOT / "references" / "evogym_api_reference.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.actions


def test_tutorial_env_gives_evogyms_observations_and_rewards_for_a_whole_episode(tutorial_dir):
    from envs.simple_env import SimpleWalkerEnvClass
    d, actions = np.load(DATA / "simple_env.npz", allow_pickle=False), _actions()
    env = SimpleWalkerEnvClass(d["body"], d["connections"])
    obs0, _ = env.reset()
    assert np.abs(obs0 - d["obs0"]).max() < 1e-9
    obs, rew, done = [], [], []
    for t in range(len(d["reward"])):
        o, r, dn, _, _ = env.step(actions(t, env.action_space.shape[0]))
        obs.append(o)
        rew.append(r)
        done.append(dn)
    assert len(d["reward"]) == 500  # evogym's whole episode (max_episode_steps=500)
    assert np.abs(np.array(obs) - d["obs"]).max() < 1e-9
    assert np.abs(np.array(rew) - d["reward"]).max() < 1e-9
    np.testing.assert_array_equal(done, d["done"])
    assert abs(np.sum(d["reward"])) > 0.1  # the robot moves: the comparison has content


def test_tutorial_env_registers_and_makes_through_gym(tutorial_dir):
    import envs  # noqa: F401  (registers SimpleWalkingEnv-v0, as the tutorial does)
    d = np.load(DATA / "simple_env.npz", allow_pickle=False)
    env = gym.make("SimpleWalkingEnv-v0", body=d["body"], render_mode="rgb_array")
    obs, _ = env.reset()
    assert np.abs(obs - d["obs0"]).max() < 1e-9
    img = env.render()
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    assert env.spec.max_episode_steps == 500


def test_basic_api_runs_until_it_asks_for_a_window_and_then_says_there_is_no_display(tutorial_dir, capsys):
    with pytest.raises(RuntimeError, match="render\\('screen'\\) needs a display"):
        runpy.run_path(str(TUTORIALS / "basic_api.py"), run_name="__main__")
    printed = capsys.readouterr().out
    assert printed.count("\n0 | F F F") == 2  # pretty_print ran twice (before and with the robot)


class _Stop(Exception):
    pass


def test_rendering_options_to_numpy_array_draws_frames(tutorial_dir, monkeypatch):
    """Headless: cv2 (not a dependency) is a stub that keeps the first frames and stops the
    1000-frame loop after 5 of them."""
    frames = []

    def imshow(title, img):
        frames.append(img)
        if len(frames) == 5:
            raise _Stop

    cv2 = types.SimpleNamespace(cvtColor=lambda img, code: img[..., ::-1], COLOR_RGB2BGR=4,
                                waitKey=lambda ms: None, imshow=imshow, destroyAllWindows=lambda: None)
    monkeypatch.setitem(sys.modules, "cv2", cv2)
    monkeypatch.setattr(sys, "argv", ["rendering_options.py", "--render-option", "to-numpy-array"])
    with pytest.raises(_Stop):
        runpy.run_path(str(TUTORIALS / "rendering_options.py"), run_name="__main__")
    assert all(f.shape == (600, 1200, 3) and f.dtype == np.uint8 for f in frames)
    assert len({f.tobytes() for f in frames}) > 1  # the robot moves between frames
