"""A short SGR run on every registered task (issue 14, acceptance 3): two generations write their
rows, and the champion.json alone replays to its recorded fitness."""

import csv
import math

import pytest

from evolve.records.champion import read_champion
from evolve.records.replay import replay_champion
from evolve.runs.experiment import Experiment
from tasks.specs import TASKS

pytestmark = pytest.mark.slow

STEPS = 5
# every task, BidirectionalWalker-v0 (random goals) too: rollouts seed every world alike, so a
# body's fitness does not depend on its slot in the batch and champion.json replays to it
# BridgeWalker-v0 and Climber-v1 (worlds of a bigger capacity tier: ~50 s each to compile their
# kernels from a cold cache) run with `-m long`; tests/tsim/test_kernels.py simulates both in the suite
BIG_TIER = ("BridgeWalker-v0", "Climber-v1")
NAMES = [pytest.param(n, marks=pytest.mark.long) if n in BIG_TIER else n for n in TASKS]


@pytest.mark.parametrize("name", NAMES)
def test_a_short_sgr_run_on_every_task(tmp_path, name):
    out = tmp_path / name
    exp = Experiment.from_config({"method": "sgr", "task": name, "generations": 2, "pop_size": 4,
                                  "episode_steps": STEPS, "workers": 1, "render_champion": False,
                                  "checkpoint_every": 1, "robust": None, "final_selection": None}, out,
                                 quiet=True)
    try:
        exp.run_all()
    finally:
        exp.close()
    with open(out / "generations.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2
    assert all(math.isfinite(float(r["best"])) for r in rows)
    champ, body, ctrl = read_champion(out)
    assert champ["task"] == name
    assert replay_champion(out)[0] == pytest.approx(champ["fitness"], abs=1e-9)


@pytest.mark.parametrize("name", ["Catcher-v0", "BidirectionalWalker-v0"])
def test_a_randomised_task_champion_replays_evolutions_episode_in_every_world(tmp_path, name):
    """Evolution, the champion's replays (report's robustness column) and its GIF all use the
    episode of a constructed env seeded 0: noise-free replays in every world of the batch score
    the champion's fitness, so perturbed ones differ from it by their action noise alone."""
    out = tmp_path / name
    exp = Experiment.from_config({"method": "sgr", "task": name, "generations": 1, "pop_size": 4,
                                  "episode_steps": 40, "workers": 1, "render_champion": False,
                                  "robust": None, "final_selection": None}, out, quiet=True)
    try:
        exp.run_all()
    finally:
        exp.close()
    champ = read_champion(out)[0]
    returns = replay_champion(out, replays=3, eps=0.0)
    assert returns == pytest.approx([champ["fitness"]] * 4, abs=1e-9)
