"""A champion is one call away: `load_champion` gives body, policy and episode length, whatever
the controller's format, and its gymnasium episode returns the recorded fitness exactly."""

import json

import numpy as np
import pytest

from evolve import Experiment, config_from_dict, load_champion


@pytest.mark.parametrize("method", ["sgr", "direct"])  # DenseController, GraphController
def test_a_champion_replays_its_fitness_exactly_in_gymnasium(tmp_path, method):
    exp = Experiment.from_config({"method": method, "task": "Walker-v0", "generations": 2, "pop_size": 8,
                                  "episode_steps": 30, "workers": 1, "render_champion": False,
                                  "robust": None, "final_selection": None}, tmp_path / "run", quiet=True)
    exp.run_all()
    exp.close()
    champ = load_champion(tmp_path / "run")
    record = json.loads((tmp_path / "run" / "champion.json").read_text())
    assert champ.episode_steps == record["episode_steps"] == 30 and champ.task == "Walker-v0"
    assert champ.fitness == record["fitness"] != 0.0
    assert champ.rollout() == champ.fitness  # bit for bit
    env = champ.env()
    obs, _ = env.reset(seed=0)
    assert env.spec.max_episode_steps == 30
    assert champ.policy(obs).shape == env.action_space.shape
    assert np.array_equal(champ.body, np.asarray(record["body"]))


def test_runs_record_the_episode_length_they_use():
    """null stands for the paper's length (Climber-v2: 400 steps), "evogym" for evogym's (1000);
    the resolved config, which the run stores, holds the number."""
    base = {"method": "sgr", "task": "Climber-v2"}
    assert config_from_dict(base).episode_steps == 400
    assert config_from_dict({**base, "episode_steps": None}).episode_steps == 400
    assert config_from_dict({**base, "episode_steps": "evogym"}).episode_steps == 1000
    assert config_from_dict({**base, "episode_steps": 7}).episode_steps == 7


def test_an_old_champion_with_a_null_episode_length_still_loads(tmp_path):
    """Champions written before runs recorded their episode length say null: the paper's length."""
    from tasks.env import obs_dim
    n_in = obs_dim("Walker-v0", 8)
    ctrl = {"layers": [{"weights": np.zeros((n_in, 3)).tolist(), "biases": [0.0] * 3, "activation": "tanh"}],
            "input_size": n_in, "action_cells": [0, 1, 2]}
    (tmp_path / "champion.json").write_text(json.dumps(
        {"task": "Walker-v0", "episode_steps": None, "fitness": 0.1, "body": [[3, 3, 3]],
         "controller": ctrl}))
    champ = load_champion(tmp_path)
    assert champ.episode_steps == 500 and champ.env().spec.max_episode_steps == 500
