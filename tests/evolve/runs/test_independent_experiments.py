"""Experiments are independent in one process: neat-python draws from the global `random`, and
each search keeps its own state of it, so two experiments stepped in turn (a notebook, a parameter
loop) give exactly the generations each gives alone, and the caller's `random` is left as it was."""

import random

from evolve.runs.experiment import Experiment

TIMINGS = ("build_s", "sim_s", "neat_s", "total_s")


def config(repo_root, seed: int) -> dict:
    return {"method": "sgr", "task": "Walker-v0", "generations": 3, "pop_size": 12, "episode_steps": 20,
            "seed": seed, "render_champion": False, "workers": 1, "robust": None, "final_selection": None,
            "neat_config": str(repo_root / "configs/neat/sgr.ini")}


def generations(exp: Experiment) -> list[dict]:
    row = exp.search.step()
    return {k: v for k, v in row.items() if k not in TIMINGS} | {"keys": sorted(exp.search.population)}


def test_two_experiments_stepped_in_turn_give_the_generations_each_gives_alone(tmp_path, repo_root):
    alone = {}
    for seed in (0, 1):
        with Experiment.from_config(config(repo_root, seed), tmp_path / f"alone{seed}", quiet=True) as exp:
            alone[seed] = [generations(exp) for _ in range(3)]
    assert alone[0] != alone[1]  # two different runs (else the test could not tell them apart)
    with (Experiment.from_config(config(repo_root, 0), tmp_path / "a", quiet=True) as a,
          Experiment.from_config(config(repo_root, 1), tmp_path / "b", quiet=True) as b):
        turns = {0: [], 1: []}
        for _ in range(3):
            turns[0].append(generations(a))
            random.random()  # the caller's own draws change nothing either
            turns[1].append(generations(b))
    assert turns == alone


def test_a_search_leaves_the_callers_random_as_it_was(tmp_path, repo_root):
    random.seed(1234)
    expected = random.getstate()
    with Experiment.from_config(config(repo_root, 0), tmp_path / "r", quiet=True) as exp:
        exp.search.step()
    assert random.getstate() == expected
