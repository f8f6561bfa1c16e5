"""What `print(x)` shows for the objects a user holds (a champion, an elite, a run, an env, a
controller): one short line that says what it is, never a dump of every weight array (a map-elites
elite's repr was 10,862 characters)."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import tasks  # noqa: F401 - registers the sgr/ ids
from evolve.records.replay import load_champion
from evolve.records.rundir import RunDir
from tasks.env import BatchEnv

ROOT = Path(__file__).resolve().parents[1]
MOST = 400
BODY = np.array([[3, 3, 3, 3, 3], [3, 3, 3, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3]])


@pytest.mark.parametrize("run, cell, controller", [
    ("results/paper/runs/sgr-Walker-v0-s0", None, "DenseController("),
    ("results/paper/runs/nested-Walker-v0-s0", None, "GraphController("),
    ("results/map-elites/runs/map-elites-Climber-v2-s0", "best", "DenseController("),
])
def test_a_champion_or_elite_prints_as_one_short_line_naming_its_task_body_and_fitness(run, cell, controller):
    if cell == "best":  # an elite of the map: its best cell
        from evolve.records.elites import read_elites

        elites = read_elites(ROOT / run)["elites"]
        cell = max(elites, key=lambda e: e["champion"]["fitness"])["cell"]
    champ = load_champion(ROOT / run, cell=cell)
    text = repr(champ)
    assert len(text) < MOST and "\n" not in text, text
    assert f"task={champ.task!r}" in text and controller in text
    assert f"fitness={champ.fitness:.6g}" in text and "actuators" in text
    if cell is not None:
        assert f"cell={tuple(cell)}" in text


def test_a_run_an_env_and_a_vector_env_print_as_one_short_line():
    for obj, starts in ((RunDir("runs/x"), "RunDir('runs/x')"),
                        (BatchEnv("Walker-v0", [BODY] * 3), "BatchEnv('Walker-v0', 3 robots"),
                        (gym.make("sgr/Walker-v0", body=BODY).unwrapped, "SgrEnv('Walker-v0', 5x5 body"),
                        (gym.make_vec("sgr/Walker-v0", num_envs=2, body=BODY), "SgrVectorEnv(")):
        text = repr(obj)
        assert text.startswith(starts) and len(text) < MOST and "\n" not in text, text
