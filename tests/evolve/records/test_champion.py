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


def _hand_made(folder, **changes) -> None:
    from tasks.env import obs_dim
    n_in = obs_dim("Walker-v0", 8)
    ctrl = {"layers": [{"weights": np.zeros((n_in, 3)).tolist(), "biases": [0.0] * 3, "activation": "tanh"}],
            "input_size": n_in, "action_cells": [0, 1, 2]}
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "champion.json").write_text(json.dumps(
        {"task": "Walker-v0", "episode_steps": 10, "fitness": 0.1, "body": [[3, 3, 3]], "controller": ctrl,
         **changes}))


@pytest.mark.parametrize("changes, words", [
    ({"fitness": None}, "key 'fitness' must be a number"),      # was float()'s TypeError
    ({"fitness": "high"}, "key 'fitness' must be a number"),    # a ValueError naming nothing
    ({"fitness": True}, "key 'fitness' must be a number"),      # was 1.0
    ({"fitness": 10**400}, "key 'fitness' must be a number"),   # an OverflowError
    ({"task": ["Walker-v0"]}, "key 'task': unknown task"),      # unhashable type
    ({"evaluation": "x"}, "key 'evaluation' must be a mapping"),  # an AttributeError when rescored
])
def test_a_champion_record_with_a_field_of_the_wrong_kind_is_refused_naming_the_key(tmp_path, changes,
                                                                                    words):
    """load_champion now says what `sgr report` (champion_of) says of the same file."""
    from tsim.errors import SgrError

    _hand_made(tmp_path / "run", **changes)
    with pytest.raises(SgrError, match=f"champion.json: {words}"):
        load_champion(tmp_path / "run")


def test_load_champion_given_champion_json_asks_for_the_run_folder(tmp_path):
    from tsim.errors import SgrError

    _hand_made(tmp_path / "run")
    assert load_champion(tmp_path / "run").fitness == 0.1
    with pytest.raises(SgrError, match="is a file: give its run's folder"):
        load_champion(tmp_path / "run" / "champion.json")


@pytest.mark.parametrize("kwargs, words", [
    ({"replays": -1}, "replays must be an integer from 0 to 100,000, got -1"),  # returned []
    ({"replays": 2.5}, "replays must be an integer"),
    ({"replays": True}, "replays must be an integer"),
    ({"replays": 2, "eps": float("inf")}, "finite numbers >= 0, got inf"),  # said the actions were
])
def test_replaying_with_arguments_that_are_not_counts_or_scales_is_refused(tmp_path, kwargs, words):
    from evolve.records.replay import replay_champion
    from tsim.errors import SgrError

    _hand_made(tmp_path / "run")
    with pytest.raises(SgrError, match=words):
        replay_champion(tmp_path / "run", **kwargs)
    with pytest.raises(SgrError, match=words):
        load_champion(tmp_path / "run").verdict(kwargs["replays"], kwargs.get("eps", 0.001))
