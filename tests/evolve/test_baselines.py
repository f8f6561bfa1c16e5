"""The paper's baselines run end to end on all four tasks from their shipped configs, write the
same run directory as SGR (with episodes per generation), and the nested one resumes exactly."""

import json

import numpy as np
import pytest

from evolve.champion import load_champion
from evolve.cli import main
from evolve.experiment import Experiment
from evolve.neat_search import NeatSearch
from evolve.rundir import RunDir
from tasks.env import BatchEnv

TASKS = ["Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0"]


def _tiny(tmp_path, repo_root, method, task, **extra):
    import yaml

    cfg = yaml.safe_load((repo_root / f"configs/{method}/{task}.yaml").read_text())
    cfg.update({"generations": 2, "pop_size": 6, "episode_steps": 8, "render_champion": False, **extra})
    for key in ("neat_config", "controller_neat_config"):
        if key in cfg:
            cfg[key] = str((repo_root / f"configs/{method}" / cfg[key]).resolve())
    if method == "nested":
        cfg.update(inner_pop_size=4, inner_generations=2)
    p = tmp_path / f"{method}-{task}.yaml"
    p.write_text(yaml.safe_dump(cfg))
    return p


@pytest.mark.parametrize("method", ["direct", "nested"])
@pytest.mark.parametrize("task", TASKS)
def test_baseline_runs_end_to_end_and_its_champion_replays(tmp_path, repo_root, monkeypatch, method,
                                                          task):
    _run_and_replay(tmp_path, repo_root, monkeypatch, method, task)


def test_direct_per_cell_layout_runs_and_its_champion_replays(tmp_path, repo_root, monkeypatch):
    champ = _run_and_replay(tmp_path, repo_root, monkeypatch, "direct", "ObstacleTraverser-v1",
                            layout="per_cell")
    cells = champ["controller"]["cell_inputs"]
    assert cells is not None and len(cells) == len(champ["controller"]["action_cells"])


def _run_and_replay(tmp_path, repo_root, monkeypatch, method, task, **extra) -> dict:
    # size of the outer population each generation is told about (the outer search is the one with
    # an evaluate callable; the nested baseline's inner controller searches have none)
    sizes = []
    tell = NeatSearch.tell

    def spy(self, *a, **kw):
        if self.evaluate is not None:
            sizes.append(len(self.population))
        return tell(self, *a, **kw)

    monkeypatch.setattr(NeatSearch, "tell", spy)
    out = tmp_path / "run"
    assert main(["evolve", "--config", str(_tiny(tmp_path, repo_root, method, task, **extra)),
                 "--out", str(out), "--quiet"]) == 0
    rows = RunDir(out).rows()
    assert [int(r["generation"]) for r in rows] == [0, 1]
    # every genome of a generation is counted as valid or invalid: the first generation holds exactly
    # pop_size (6) genomes, later ones what neat-python's reproduction made (about pop_size)
    assert sizes[0] == 6
    assert [int(r["n_valid"]) + int(r["n_invalid"]) for r in rows] == sizes
    if method == "direct":  # generation 0 has no elites: each valid genome is simulated once
        assert int(rows[0]["episodes"]) == int(rows[0]["n_valid"])
    champ, body, ctrl = load_champion(out)
    assert champ["method"] == method and champ["task"] == task
    assert champ["controller"]["format"] == "sgr-graph-controller-1"
    # the JSON controller alone reproduces the champion's recorded fitness
    env = BatchEnv(task, [body], episode_steps=8)
    obs, total = env.reset(), 0.0
    for _ in range(8):
        obs, r, term, trunc, _ = env.step([ctrl.act(obs[0, :env.obs_dims[0]])])
        total += r[0]
        if term[0]:
            break
    assert total == pytest.approx(champ["fitness"], abs=1e-9)
    if method == "nested":  # inner episodes: at most bodies x inner_pop_size x inner_generations
        assert all(0 < int(r["episodes"]) <= int(r["n_valid"]) * 4 * 2 for r in rows)
    return champ


def test_nested_run_resumes_with_identical_numbers(tmp_path, repo_root):
    p = _tiny(tmp_path, repo_root, "nested", "Walker-v0", generations=3, checkpoint_every=1)
    full = Experiment.create(str(p), str(tmp_path / "full"), {}, quiet=True)
    full.run_all()
    part = Experiment.create(str(p), str(tmp_path / "part"), {}, quiet=True)
    part.search.step = _die_after(part.search.step, 2)
    with pytest.raises(KeyboardInterrupt):
        part.run_all()
    part.close()  # what the process's end would do: release the run's lock
    Experiment.resume(str(tmp_path / "part"), quiet=True).run_all()
    cols = ["best", "mean", "median", "n_valid", "episodes"]
    a = [[r[c] for c in cols] for r in RunDir(tmp_path / "full").rows()]
    b = [[r[c] for c in cols] for r in RunDir(tmp_path / "part").rows()]
    assert len(a) == 3 and a == b
    assert json.loads((tmp_path / "full/champion.json").read_text()) == \
        json.loads((tmp_path / "part/champion.json").read_text())
    assert np.isfinite(float(a[-1][0]))


def _die_after(step, n):
    calls = {"n": 0}

    def dying():
        calls["n"] += 1
        if calls["n"] > n:
            raise KeyboardInterrupt
        return step()
    return dying
