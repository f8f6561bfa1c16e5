"""The paper's baselines run end to end on all four tasks from their shipped configs, write the
same run directory as SGR (with episodes per generation), and the nested one resumes exactly."""

import json

import numpy as np
import pytest

from evolve.cli import main
from evolve.records.champion import read_champion
from evolve.records.replay import replay_champion, rescore_champion
from evolve.records.rundir import RunDir
from evolve.runs.experiment import Experiment
from evolve.search.neat_search import NeatSearch

pytestmark = pytest.mark.slow

TASKS = ["Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0"]


def _tiny(shipped_config, method, task, **extra):
    nested = {"inner_pop_size": 4, "inner_generations": 2} if method == "nested" else {}
    # one rollout process (the packaged configs' `workers: auto` would start one per CPU):
    # tests/evolve/rollout/test_pool.py holds every method's runs equal on one or two workers
    return shipped_config(method, task, **{"generations": 2, "pop_size": 6, "episode_steps": 8,
                                           "render_champion": False, "workers": 1, **extra, **nested})


@pytest.mark.parametrize("method", ["direct", "nested"])
@pytest.mark.parametrize("task", TASKS)
def test_baseline_runs_end_to_end_and_its_champion_replays(tmp_path, shipped_config, monkeypatch,
                                                          method, task):
    _run_and_replay(tmp_path, shipped_config, monkeypatch, method, task)


def test_direct_per_cell_layout_runs_and_its_champion_replays(tmp_path, shipped_config, monkeypatch):
    champ = _run_and_replay(tmp_path, shipped_config, monkeypatch, "direct", "ObstacleTraverser-v1",
                            layout="per_cell")
    cells = champ["controller"]["cell_inputs"]
    assert cells is not None and len(cells) == len(champ["controller"]["action_cells"])


def _run_and_replay(tmp_path, shipped_config, monkeypatch, method, task, **extra) -> dict:
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
    assert main(["evolve", "--config", str(_tiny(shipped_config, method, task, **extra)),
                 "--out", str(out), "--quiet"]) == 0
    rows = RunDir(out).rows()
    assert [int(r["generation"]) for r in rows] == [1, 2]  # counted from 1
    # every genome of a generation is counted as valid or invalid: the first generation holds exactly
    # pop_size (6) genomes, later ones what neat-python's reproduction made (about pop_size)
    assert sizes[0] == 6
    assert [int(r["n_valid"]) + int(r["n_invalid"]) for r in rows] == sizes
    if method == "direct":  # generation 0 has no elites: each valid genome is simulated once
        assert int(rows[0]["episodes"]) == int(rows[0]["n_valid"])
    champ, body, ctrl = read_champion(out)
    assert champ["method"] == method and champ["task"] == task
    # direct's network is its genome, which the file holds: recorded as the genome's compiled form
    # (issue 36); nested's controller is an inner population's genome: in full
    derived = "sgr-genome-graph-controller-1"
    assert champ["controller"]["format"] == (derived if method == "direct" else "sgr-graph-controller-1")
    # the JSON controller alone reproduces the champion's recorded fitness: the packaged configs
    # score under noise (honest by default), so over the same perturbed episodes
    assert champ["evaluation"]["robust"] is not None
    assert rescore_champion(out) == pytest.approx(champ["fitness"], abs=1e-9)
    if method == "nested":  # inner episodes: at most bodies x inner_pop_size x inner_generations
        assert all(0 < int(r["episodes"]) <= int(r["n_valid"]) * 4 * 2 for r in rows)
    return champ


def test_nested_run_resumes_with_identical_numbers(tmp_path, shipped_config):
    p = _tiny(shipped_config, "nested", "Walker-v0", generations=3, checkpoint_every=1)
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


def test_nested_inner_populations_stay_bounded_and_the_champion_keeps_its_controller(tmp_path,
                                                                                    shipped_config):
    """With inner_keep_generations K, only the bodies of the last K outer generations and the
    champion's body keep an inner population; the champion JSON still replays to its fitness."""
    keep = 2
    p = _tiny(shipped_config, "nested", "Walker-v0", generations=8, inner_keep_generations=keep,
              robust=None)  # the exact episode: replay_champion's first return is the fitness
    exp = Experiment.create(str(p), str(tmp_path / "run"), {}, quiet=True)
    seen: list[set[bytes]] = []
    evaluate = exp.problem.evaluate

    def recording(phenotypes):
        seen.append({ph.body.tobytes() for ph in phenotypes})
        return evaluate(phenotypes)
    exp.search.evaluate = recording
    kept = []
    exp.run_all(after_generation=lambda e: kept.append((set(e.problem.inner), e.problem.pinned)))
    exp.close()
    assert len(kept) == 8
    for g, (inner, pinned) in enumerate(kept):
        recent = set().union(*seen[max(0, g + 1 - keep):g + 1])
        assert inner <= recent | {pinned} and len(inner) <= len(recent) + 1
    assert len(set().union(*seen)) > len(exp.problem.inner), "no inner population was forgotten"
    champ, body, ctrl = read_champion(tmp_path / "run")
    assert exp.problem.pinned == np.array(champ["body"], dtype=np.int64).tobytes()
    assert replay_champion(tmp_path / "run")[0] == pytest.approx(champ["fitness"], abs=1e-9)


def test_nested_champion_body_is_pinned_while_absent_bodies_are_forgotten(repo_root):
    from evolve.methods.nested import BodyPhenotype, NestedProblem
    from evolve.runs.config import load_config
    from evolve.search.neat_ini import neat_config_from_text, neat_ini_text

    cfg = load_config(repo_root / "configs/nested/Walker-v0.yaml",
                      {"inner_pop_size": 4, "inner_generations": 1, "episode_steps": 4,
                       "inner_keep_generations": 2})
    neat_config = neat_config_from_text(neat_ini_text(cfg.neat_config, cfg.pop_size,
                                                      NestedProblem.neat_overrides(cfg)))
    problem = NestedProblem(cfg, neat_config)
    champ, other, third = (np.full((5, 5), 3), np.full((5, 5), 4), np.full((5, 5), 1))
    champ[0], third[4] = 0, 3
    as_phenotypes = lambda *bodies: [BodyPhenotype(b, True) for b in bodies]
    problem.evaluate(as_phenotypes(champ, other))                  # generation 0
    problem.champion(BodyPhenotype(champ, True))
    problem.evaluate(as_phenotypes(third))                         # 1: champ, other absent once
    assert set(problem.inner) == {champ.tobytes(), other.tobytes(), third.tobytes()}
    problem.evaluate(as_phenotypes(third))                         # 2: absent twice -> forgotten
    assert set(problem.inner) == {champ.tobytes(), third.tobytes()}
    assert set(problem.last_seen) == set(problem.inner)
    problem.champion(BodyPhenotype(champ, True))                   # its controller is still there
    restored = NestedProblem(cfg, neat_config)
    restored.restore(NestedProblem.decode_state(json.loads(json.dumps(problem.state())), cfg))
    assert (restored.generation, restored.last_seen, restored.pinned) == \
        (problem.generation, problem.last_seen, problem.pinned)
    problem.evaluate(as_phenotypes(other))                         # 3: back, with a fresh population
    assert problem.inner[other.tobytes()].generation == 1
    problem.pool.close()
    # a run whose config.yaml predates the key (resumed from its raw config) forgets nothing
    old = {k: v for k, v in cfg.to_yaml().items() if k != "inner_keep_generations"}
    assert NestedProblem(old, neat_config).keep_generations is None
