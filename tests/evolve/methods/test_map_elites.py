"""The map-elites method's archive and its `qd` config key (evolve/methods/map_elites.py): a cell keeps
the better elite, bad `qd` keys are one line naming the key, and a missing pyribs says how to install
it. Runs (resume, workers, elites replayed): tests/evolve/runs/test_map_elites_run.py."""

from __future__ import annotations

import sys

import neat
import numpy as np
import pytest
import yaml

from evolve.cli import main
from evolve.methods.map_elites import Elite, MapElitesProblem, MapElitesSearch, require_ribs
from evolve.methods.qd_floors import FLOORS
from evolve.runs.config import config_from_dict
from evolve.search.neat_ini import neat_config_from_text, neat_ini_text
from tsim.errors import SgrError

BASE = {"method": "map-elites", "task": "Walker-v0", "robust": None, "final_selection": None}


def needs_ribs():
    pytest.importorskip("ribs", reason="method map-elites needs pyribs: pip install 'sgr[qd]'")


def search_of(qd: dict) -> MapElitesSearch:
    """A fresh search of a config with `qd`, nothing evaluated."""
    cfg = config_from_dict({**BASE, "qd": qd})
    ini = neat_ini_text(cfg.neat_config, cfg.pop_size, MapElitesProblem.neat_overrides(cfg))
    nc = neat_config_from_text(ini, cfg.neat_config)
    return MapElitesSearch(MapElitesProblem(cfg, nc), nc, seed=0)


def elite(key: int, fitness: float, measures: tuple[float, float]) -> Elite:
    return Elite(neat.DefaultGenome(key), None, np.array(measures), fitness, [f"0/{key}"], 0)


def keys(search: MapElitesSearch) -> dict[int, int]:
    return {cell: e.genome.key for cell, e in search.elites.items()}


def test_an_insertion_keeps_the_better_elite_of_a_cell():
    """2x2 cells over actuator x rigid in [0, 1]: (0.1, 0.1) and (0.3, 0.2) share cell (0, 0); (0.9, 0.1)
    is cell (1, 0). A worse newcomer leaves the elite, a better one replaces it, and of two newcomers
    to one cell the better one takes it; other cells are untouched."""
    needs_ribs()
    s = search_of({"descriptors": ["actuator", "rigid"], "resolution": [2, 2]})
    s.insert([elite(1, 1.0, (0.1, 0.1)), elite(2, 0.2, (0.9, 0.1))])
    low, right = s.archive.grid_to_int_index([[0, 0], [1, 0]]).tolist()
    assert keys(s) == {low: 1, right: 2}
    s.insert([elite(3, 0.5, (0.3, 0.2))])  # worse than elite 1
    assert keys(s) == {low: 1, right: 2}
    s.insert([elite(4, 1.5, (0.3, 0.2))])  # better
    assert keys(s) == {low: 4, right: 2}
    s.insert([elite(5, 3.0, (0.2, 0.4)), elite(6, 2.0, (0.4, 0.3))])  # two newcomers, one cell
    assert keys(s) == {low: 5, right: 2}
    assert s.best["key"] == 5 and s.best["fitness"] == 3.0 and s.best["cell"] == (0, 0)
    assert s.elites[low].genome.fitness == 3.0  # what crossover and final selection read
    assert s.archive.stats.num_elites == 2
    assert s.qd_score() == pytest.approx(3.0 + 0.2 - 2 * s.qd.score_offset)


def test_a_rescored_elite_that_falls_is_replaced_by_a_newcomer_it_used_to_beat():
    """Re-scoring lowers an elite's mean (pyribs alone never lowers a cell): the archive is rebuilt
    from the elites' current fitness, so a newcomer between the old and the new mean takes the cell;
    an elite whose mean is NaN leaves the archive."""
    needs_ribs()
    s = search_of({"descriptors": ["actuator", "rigid"], "resolution": [2, 2]})
    s.insert([elite(1, 2.0, (0.1, 0.1)), elite(2, 1.0, (0.9, 0.1))])
    cell = s.archive.grid_to_int_index([[0, 0]]).tolist()[0]
    s.elites[cell].total, s.elites[cell].tags = 2.0 + 0.0, ["0/1", "1/1"]  # mean 1.0
    first = s.elites[cell]
    s.insert([elite(3, 1.5, (0.2, 0.2))])
    assert s.elites[cell].genome.key == 3 and first.fitness == 1.0
    other = s.archive.grid_to_int_index([[1, 0]]).tolist()[0]
    s.elites[other].total = float("nan")
    s.insert([])
    assert other not in s.elites and len(s.archive) == 1


@pytest.mark.parametrize("qd, named", [
    ({"cells": 3}, "key 'qd': unknown key 'cells'"),
    ({"descriptors": ["actuator", "wings"]}, "key 'qd.descriptors': unknown descriptor 'wings'"),
    ({"descriptors": "actuator"}, "key 'qd.descriptors' must be a list"),
    ({"descriptors": ["rigid", "rigid"]}, "key 'qd.descriptors' must be a list of distinct"),
    ({"resolution": [10, 0]}, "key 'qd.resolution' must be an int >= 1 or a list"),
    ({"resolution": [10, 10, 10]}, "key 'qd.resolution' must be an int >= 1 or a list"),
    ({"ranges": {"actuator": [1, 0]}}, "key 'qd.ranges.actuator' must be [low, high]"),
    ({"ranges": {"width": [0, 5]}}, "key 'qd.ranges': 'width' is not one of qd.descriptors"),
    ({"batch": 0}, "key 'qd.batch' must be an int from 1 to 1,000,000, got 0"),
    ({"initial": 2.5}, "key 'qd.initial' must be an int from 1 to 1,000,000, got 2.5"),
    ({"batch": 10**9}, "key 'qd.batch' must be an int from 1 to 1,000,000, got 1000000000"),
    ({"rescore": -1}, "key 'qd.rescore' must be an int from 0 to 1,000,000, got -1"),
    ({"score_offset": "low"}, "key 'qd.score_offset' must be a number or 'auto'"),
    ({"selection": "greedy"}, "key 'qd.selection' must be one of uniform, curiosity"),
    ({"exploit": 1.5}, "key 'qd.exploit' must be a share from 0 to 1"),
    ({"descriptors": ["gait", "contact"]}, "key 'qd.descriptors': unknown descriptor 'gait'"),
])
def test_a_bad_qd_key_is_one_line_naming_it(tmp_path, capsys, qd, named):
    """Through `sgr evolve --config`: exit 2 and one line on stderr naming the key; nothing is run."""
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(yaml.safe_dump({**BASE, "qd": qd}))
    assert main(["evolve", "--config", str(cfg), "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and named in err, err
    assert not (tmp_path / "run").exists()


def test_the_defaults_fill_every_qd_key():
    """{} (or no `qd` at all): actuator x rigid at 10 x 10 over [0, 1], batch = pop_size, initial =
    batch, rescore = batch / 4; width's range is one cell per column of the robot's grid."""
    needs_ribs()
    p = search_of({}).qd
    assert (p.descriptors, p.resolution) == (("actuator", "rigid"), (10, 10))
    assert p.ranges == ((0.0, 1.0), (0.0, 1.0))
    assert (p.batch, p.initial, p.rescore) == (128, 128, 32)
    assert (p.selection, p.exploit) == ("uniform", 0.0)  # the search of runs made before they existed
    assert p.score_offset == FLOORS["Walker-v0"] < 0  # the task's floor (evolve/methods/qd_floors.py)
    w = search_of({"descriptors": ["width"]}).qd
    assert w.resolution == (5,) and w.ranges == ((0.5, 5.5),)
    assert search_of({"batch": 3}).qd.rescore == 1  # a small batch still re-scores: honest by default


def test_without_accumulate_the_elites_scored_longest_ago_are_rescored_first():
    """With `reevaluate` alone an elite's fitness is its latest score, so re-scoring must come round
    to every elite: the cells picked are those whose latest tag (`<generation>/<key>`) is oldest,
    not the lowest cells every time."""
    needs_ribs()
    robust = {"episodes": 1, "action_noise": "uniform", "action_scale": 0.001, "reevaluate": True,
              "accumulate": False}
    cfg = config_from_dict({**BASE, "robust": robust, "qd": {"descriptors": ["actuator", "rigid"],
                                                             "resolution": [2, 2], "rescore": 2}})
    ini = neat_ini_text(cfg.neat_config, cfg.pop_size, MapElitesProblem.neat_overrides(cfg))
    nc = neat_config_from_text(ini, cfg.neat_config)
    s = MapElitesSearch(MapElitesProblem(cfg, nc), nc, seed=0)
    s.insert([elite(1, 1.0, (0.1, 0.1)), elite(2, 1.0, (0.9, 0.1)), elite(3, 1.0, (0.1, 0.9)),
              elite(4, 1.0, (0.9, 0.9))])
    by_key = {e.genome.key: c for c, e in s.elites.items()}
    for key, last in ((1, "5/1"), (2, "2/2"), (3, "7/3"), (4, "3/4")):
        s.elites[by_key[key]].tags = [last]
    assert s._to_rescore() == [by_key[2], by_key[4]]


def test_without_pyribs_the_method_says_how_to_install_it_in_one_line(monkeypatch):
    monkeypatch.setitem(sys.modules, "ribs.archives", None)  # import fails as if not installed
    monkeypatch.setitem(sys.modules, "ribs", None)
    with pytest.raises(SgrError) as exc:
        require_ribs()
    assert str(exc.value) == ("method 'map-elites' needs pyribs, which is not installed: "
                              "pip install 'sgr[qd]' (or: pip install ribs)")
    with pytest.raises(SgrError, match="pip install 'sgr\\[qd\\]'"):
        config_from_dict({**BASE})


def test_every_task_has_a_map_elites_config_with_the_budget_of_sgrs_100_generations(repo_root):
    """`sgr evolve --method map-elites --task T` finds a packaged config for each of the 32 tasks; its
    episodes at most, generations x (batch + rescore), are within 5 % of what SGR's 100 generations
    with the packaged config simulated (results/robust-fast, the four paper tasks, 3 seeds)."""
    needs_ribs()
    import argparse
    import csv

    from evolve.cli.evolve_cmd import evolve_config
    from evolve.runs.config import configs_dir, load_config
    from tasks.specs import BUILTIN

    for task in sorted(BUILTIN):
        path = evolve_config(argparse.Namespace(config=None, task=task, method="map-elites"))
        assert path == configs_dir() / "map-elites" / f"{task}.yaml"
        cfg = load_config(path)
        assert (cfg.method, cfg.task, cfg.robust.accumulate, cfg.final_selection is not None) == \
            ("map-elites", task, True, True)
    raw = yaml.safe_load((configs_dir() / "map-elites" / "Walker-v0.yaml").read_text())
    most = raw["generations"] * (raw["qd"]["batch"] + raw["qd"]["rescore"])
    runs = sorted((repo_root / "results" / "robust-fast" / "runs").glob("sgr-*-s*/generations.csv"))
    assert len(runs) == 12
    sgr = [sum(int(r["episodes"]) for r in list(csv.DictReader(f.open()))[:100]) for f in runs]
    assert abs(most - sum(sgr) / len(sgr)) <= 0.05 * sum(sgr) / len(sgr), (most, sgr)


def test_a_registered_descriptor_can_be_named_in_qd(monkeypatch):
    """Descriptors are pluggable like tasks: one registered by name (here the voxel count) is a
    `qd.descriptors` entry with its own default range and cells, measured on the body."""
    from evolve.methods import descriptors

    needs_ribs()
    monkeypatch.setitem(descriptors.DESCRIPTORS, "dummy", None)  # restored after the test
    descriptors.register("dummy", lambda body: float(np.count_nonzero(body)),
                         lambda shape: (0.0, float(shape[0] * shape[1])), lambda shape: 5)
    qd = search_of({"descriptors": ["dummy", "actuator"]}).qd
    assert qd.ranges[0] == (0.0, 25.0) and qd.resolution == (5, 10)
    body = np.array([[1, 3, 0], [2, 4, 4], [0, 0, 0]])
    assert qd.measure(body).tolist() == pytest.approx([5.0, 3 / 5], abs=1e-12)


@pytest.mark.parametrize("resolution", [100_000, [2_000, 1_000]])
def test_an_archive_too_big_to_allocate_is_one_line_naming_qd_resolution(tmp_path, capsys, resolution):
    """pyribs allocates every cell up front: 10^10 cells were a MemoryError traceback, not a line."""
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(yaml.safe_dump({**BASE, "qd": {"resolution": resolution}}))
    assert main(["evolve", "--config", str(cfg), "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "key 'qd.resolution' makes" in err, err
    assert not (tmp_path / "run").exists()


def test_every_task_has_a_floor_at_or_below_zero():
    """qd_floors.py states a floor for each of the 32 tasks, never above 0 (an elite's share of the
    QD score is max(0, fitness - floor))."""
    from tasks.specs import BUILTIN

    assert set(FLOORS) == set(BUILTIN) and all(f <= 0 for f in FLOORS.values())


@pytest.mark.parametrize("seed", range(5))
def test_the_qd_score_never_falls_as_elites_are_added(seed):
    """Property: offering random elites one batch after another (fitness below and above the offset,
    some NaN), the QD score after each insertion is at least the one before, and it is the sum of
    max(0, fitness - offset) over the elites."""
    needs_ribs()
    rng = np.random.default_rng(seed)
    s = search_of({"resolution": [4, 4], "score_offset": -1.0})
    last, key = 0.0, 0
    for _ in range(30):
        batch = []
        for _ in range(int(rng.integers(1, 6))):
            key += 1
            fit = float(rng.normal(0.0, 2.0)) if rng.random() > 0.1 else float("nan")
            batch.append(elite(key, fit, tuple(rng.random(2))))
        s.insert(batch)
        score = s.qd_score()
        assert score >= last
        assert score == pytest.approx(sum(max(0.0, e.fitness + 1.0) for e in s.elites.values()))
        last = score
    assert last > 0


def test_behaviour_descriptors_read_the_episode_s_features():
    """A behaviour descriptor reads the features the rollout recorded, a body descriptor the body; the
    problem then asks the rollout to record, and a body-only archive does not."""
    needs_ribs()
    from evolve.methods.descriptors import measure
    from tasks.behaviour import FEATURES

    s = search_of({"descriptors": ["actuator", "gait_frequency"]})
    assert s.problem.record_behaviour and not search_of({}).problem.record_behaviour
    features = np.arange(len(FEATURES), dtype=float)
    body = np.array([[3, 3], [1, 0]])
    got = measure(["actuator", "gait_frequency", "contact"], body, features)
    assert got.tolist() == [2 / 3, FEATURES.index("gait_frequency"), FEATURES.index("contact")]
    with pytest.raises(ValueError, match="describes behaviour"):
        measure(["gait_frequency"], body, None)


def test_curiosity_credits_the_parents_of_children_that_entered():
    """`selection: curiosity`: each parent of a child that took a cell gains 1, of one that did not
    loses 0.5 (Cully & Demiris 2018); parents are then drawn in proportion to their score shifted
    to start at 1, so an elite whose children keep entering is drawn more often."""
    needs_ribs()
    s = search_of({"resolution": [2, 2], "selection": "curiosity"})
    s.insert([elite(1, 1.0, (0.1, 0.1)), elite(2, 1.0, (0.9, 0.1))])
    kids = [(neat.DefaultGenome(3), None, (1, 1)), (neat.DefaultGenome(4), None, (1, 2))]
    s.insert([elite(3, 0.5, (0.1, 0.9)), elite(4, 0.1, (0.2, 0.2))])  # 3 enters, 4 does not
    s._credit(kids)
    assert s.curiosity == {1: 2.0 - 0.5, 2: -0.5}
    cells = sorted(s.elites)
    with s._own_random():
        drawn = [s._parent(cells, exploit=False).key for _ in range(3000)]
    # weights: key 1: 1.5 - (-0.5) + 1 = 3, key 2: 1, key 3 (no score yet, 0): 1.5
    share = drawn.count(1) / len(drawn)
    assert share == pytest.approx(3 / 5.5, abs=0.03)


def test_an_exploiting_parent_is_the_fittest_of_a_tournament():
    """`exploit`: its parents are the fittest of TOURNAMENT elites drawn; with every elite drawn (as
    many elites as the tournament), always the best."""
    needs_ribs()
    from evolve.methods.map_elites import TOURNAMENT

    s = search_of({"resolution": [2, 2], "exploit": 0.5})
    corners = [(0.1 + 0.5 * (k % 2), 0.1 + 0.5 * (k // 3)) for k in range(1, 1 + TOURNAMENT)]
    s.insert([elite(k, float(k), m) for k, m in enumerate(corners, start=1)])
    cells = sorted(s.elites)
    assert len(cells) == TOURNAMENT
    with s._own_random():
        assert {s._parent(cells, exploit=True).key for _ in range(50)} == {TOURNAMENT}


def test_a_generation_with_nothing_to_evaluate_ignores_the_last_batch_s_behaviour(monkeypatch):
    """No valid child and no elite to re-score: nothing is simulated, and the problem's behaviour of
    an earlier batch (here three stale rows) is not read as this generation's."""
    needs_ribs()
    s = search_of({"descriptors": ["gait_frequency", "contact"]})
    s.problem.behaviour = np.zeros((3, 7))
    monkeypatch.setattr(s, "_breed", lambda: ([], 5))
    monkeypatch.setattr(s, "_to_rescore", lambda: [])
    row = s.step()
    assert (row["n_valid"], row["n_invalid"], row["episodes"], row["n_elites"]) == (0, 5, 0, 0)
