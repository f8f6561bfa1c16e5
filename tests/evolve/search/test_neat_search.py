"""The NEAT loop: invalid bodies are counted and never simulated; speciation adds v x body distance."""

import neat
import numpy as np

from evolve.methods.sgr.decoder import DecoderSettings, decode, is_valid_robot
from evolve.search.body_distance import body_distance
from evolve.search.neat_search import NeatSearch


def test_invalid_bodies_are_counted_excluded_from_simulation_and_from_the_population(neat_config):
    cfg = neat_config(pop=40)
    seen = []

    def evaluate(phenotypes):
        seen.extend(phenotypes)
        return np.array([float(np.count_nonzero(p.body)) for p in phenotypes]), len(phenotypes)  # stand-in

    search = NeatSearch(cfg, lambda g: decode(g, cfg.genome_config, "Walker-v0", DecoderSettings()),
                        evaluate, seed=3)
    total_bad = 0
    for _ in range(3):
        pop = dict(search.population)
        bad = {k for k in pop if not is_valid_robot(search.phenotypes[k].body)}
        total_bad += len(bad)
        seen.clear()
        row = search.step()
        assert row["n_invalid"] == len(bad) and row["n_valid"] == len(pop) - len(bad)
        assert len(seen) <= len(pop) - len(bad) and all(is_valid_robot(p.body) for p in seen)
        assert not bad & set(search.population)  # not carried over as elites
    assert total_bad > 0  # the random CPPNs do produce invalid bodies, so the check above bites


def test_speciation_distance_adds_v_times_the_body_distance_scaled_to_5x5(neat_config, genomes):
    """At 5x5 the paper's eq. 1 and 2 exactly; a 10x10 body made of each cell of a 5x5 one as 2x2
    cells lies as far from another made so as the two 5x5 bodies (eq. 2 counts 4x as many cells,
    scaled by 25 / 100), and 6x9 bodies are scaled by 25 / 54."""
    cfg = neat_config()
    gc = cfg.genome_config
    a, b = genomes(cfg, 2, mutations=3)
    base = neat.DefaultGenome.distance(a, b, gc)
    rng = np.random.default_rng(0)
    body_a, body_b = rng.integers(0, 5, (5, 5)), rng.integers(0, 5, (5, 5))
    gc.body_cache = {a.key: body_a, b.key: body_b}
    gc.body_distance_weight = 0.25
    small = body_distance(body_a, body_b)
    assert small > 5 and a.distance(b, gc) == base + 0.25 * small
    gc.body_cache = {k: np.kron(m, np.ones((2, 2), dtype=int)) for k, m in ((a.key, body_a), (b.key, body_b))}
    assert body_distance(gc.body_cache[a.key], gc.body_cache[b.key]) == 4 * small
    assert a.distance(b, gc) == base + 0.25 * small
    gc.body_cache = {a.key: rng.integers(0, 5, (6, 9)), b.key: rng.integers(0, 5, (6, 9))}
    wide = body_distance(gc.body_cache[a.key], gc.body_cache[b.key])
    assert abs(a.distance(b, gc) - (base + 0.25 * wide * 25 / 54)) < 1e-12
    gc.body_distance_weight = 0.0
    assert a.distance(b, gc) == base


def test_ancestors_and_fitness_histories_stay_bounded_and_trimming_them_changes_nothing(neat_config):
    """neat-python's reproduction records the parents of every genome ever made and each species
    its whole fitness history; we keep neither (the history as its maximum), with the same run."""
    from types import SimpleNamespace

    def run(trim: bool) -> tuple:
        cfg = neat_config(pop=30)
        cfg.species_set_config.compatibility_threshold = 1.5  # many species, some stagnate

        def evaluate(phenotypes):  # rounded: ties and plateaus, so species stagnate
            return np.array([round(sum(c.weight for c in p.genome.connections.values() if c.enabled), 1)
                             for p in phenotypes]), len(phenotypes)
        search = NeatSearch(cfg, lambda g: SimpleNamespace(valid=True, body=np.zeros((5, 5)), genome=g),
                            evaluate, seed=4)
        if not trim:
            search._trim_history = lambda: None
        stagnant = []
        search.reporters.add(SimpleNamespace(species_stagnant=lambda sid, s: stagnant.append(sid),
                                             info=lambda msg: None))
        rows = [search.step() for _ in range(45)]
        longest = max(len(s.fitness_history) for s in search.species.species.values())
        fitness = [(r["best"], r["mean"], r["n_species"]) for r in rows]
        genomes = {k: sorted((c.key, c.weight) for c in g.connections.values())
                   for k, g in search.population.items()}
        return fitness, genomes, len(search.reproduction.ancestors), longest, stagnant

    trimmed, untrimmed = run(True), run(False)
    assert trimmed[:2] == untrimmed[:2]
    assert trimmed[2] == 0 and untrimmed[2] > 300
    assert trimmed[3] == 1 and untrimmed[3] > 20  # longer than max_stagnation: stagnation was decided
    assert trimmed[4] == untrimmed[4] and len(trimmed[4]) >= 3  # the same species stagnated


def _unit(text: str) -> float:
    import hashlib
    return int.from_bytes(hashlib.blake2b(text.encode(), digest_size=4).digest(), "little") / 2**32


def _tag_score(tag: str) -> float:
    """A stand-in score, a pure function of the evaluation's tag "<generation>/<key>[/race]" as robust
    noise is: the genome's quality plus a little noise, so good genomes survive as elites."""
    return _unit(tag.split("/")[1]) + 0.01 * _unit(tag)


def _accumulating_search(neat_config, race: int, seen: list):
    from types import SimpleNamespace

    def evaluate(phenotypes, tags):
        seen.extend(tags)
        return np.array([_tag_score(t) for t in tags]), len(tags)

    return NeatSearch(neat_config(pop=30), lambda g: SimpleNamespace(valid=True, body=np.ones((5, 5))),
                      evaluate, seed=2, reevaluate=True, accumulate=True, race=race)


def test_accumulated_fitness_is_the_mean_of_every_score_the_genome_had_in_order(neat_config):
    """With `accumulate`, a survivor is scored again each generation (fresh tag) and its fitness is
    the mean of all its scores, summed in the order they came: an elite's lucky first score is
    diluted rather than kept."""
    seen: list[str] = []
    search = _accumulating_search(neat_config, 0, seen)
    for _ in range(6):
        search.step()
    survivors = 0
    for key, g in search.population.items():
        if key not in search.scores:
            assert g.fitness is None  # a newborn: not scored yet
            continue
        total, tags = search.scores[key]
        expected = 0.0
        for t in tags:
            expected += _tag_score(t)
        assert g.fitness == expected / len(tags) and total == expected
        assert tags == [f"{gen}/{key}" for gen in range(int(tags[0].split("/")[0]), search.generation)]
        survivors += len(tags) > 1
    assert survivors >= 1  # an elite lived through several generations and was scored in each
    assert search.best["tags"] and all(t in seen for t in search.best["tags"])


def test_racing_gives_the_top_genomes_one_more_evaluation_each_generation(neat_config):
    """`race`: after a generation's episodes, the `race` genomes whose fitness would rank highest are
    evaluated once more (tag "<generation>/<key>/race") and that score is averaged in too."""
    seen: list[str] = []
    search = _accumulating_search(neat_config, 5, seen)
    rows = [search.step() for _ in range(3)]
    raced = [t for t in seen if t.endswith("/race")]
    assert len(raced) == 5 * 3
    for row, gen in zip(rows, range(3), strict=True):
        base = [t for t in seen if t.startswith(f"{gen}/") and not t.endswith("/race")]
        assert row["episodes"] == len(base) + 5
        ahead = sorted(base, key=lambda t: -_tag_score(t))  # newborns: one score, the rank is the score
        if gen == 0:
            assert {t.split("/")[1] for t in ahead[:5]} == {t.split("/")[1] for t in raced[:5]}


def test_accumulate_without_reevaluate_or_race_without_accumulate_is_refused(neat_config):
    import pytest
    with pytest.raises(ValueError, match="accumulate needs reevaluate"):
        NeatSearch(neat_config(pop=10), lambda g: g, None, seed=0, accumulate=True)
    with pytest.raises(ValueError, match="race and settle need accumulate"):
        NeatSearch(neat_config(pop=10), lambda g: g, None, seed=0, reevaluate=True, race=3)


def test_a_settled_genome_keeps_its_mean_and_is_not_simulated_again(neat_config):
    """`settle`: once a genome has that many scores its mean stands, and it costs no more episodes."""
    from types import SimpleNamespace

    seen: list[str] = []

    def evaluate(phenotypes, tags):
        seen.extend(tags)
        return np.array([_tag_score(t) for t in tags]), len(tags)

    search = NeatSearch(neat_config(pop=30), lambda g: SimpleNamespace(valid=True, body=np.ones((5, 5))),
                        evaluate, seed=2, reevaluate=True, accumulate=True, settle=2)
    for _ in range(6):
        search.step()
    per_key: dict[str, int] = {}
    for t in seen:
        per_key[t.split("/")[1]] = per_key.get(t.split("/")[1], 0) + 1
    assert max(per_key.values()) == 2  # nobody scored a third time
    long_lived = [k for k, (_, tags) in search.scores.items() if len(tags) == 2
                  and int(tags[-1].split("/")[0]) < search.generation - 1]
    assert long_lived  # an elite that lived on after it settled, unsimulated
    for k in long_lived:
        total, tags = search.scores[k]
        assert search.population[k].fitness == (_tag_score(tags[0]) + _tag_score(tags[1])) / 2


def _species_and_population(neat_config, shape: tuple[int, int], generations: int) -> list:
    """(n_species, population) per generation of SGR's decoding at `shape` with the packaged
    speciation (sgr.ini's threshold 3.0, body_distance_weight 0.1) and a stand-in fitness."""
    cfg = neat_config(pop=40)
    settings = DecoderSettings(shape=shape)

    def evaluate(phenotypes):  # stand-in: bigger bodies score more
        return np.array([float(np.count_nonzero(p.body)) for p in phenotypes]), len(phenotypes)

    search = NeatSearch(cfg, lambda g: decode(g, cfg.genome_config, "Walker-v0", settings), evaluate,
                        seed=1, body_distance_weight=0.1)
    out = []
    for _ in range(generations):
        row = search.step()
        out.append((row["n_species"], len(search.population)))
    return out


def test_speciation_keeps_the_population_at_pop_size_at_10x10(neat_config):
    """The body distance (eq. 2) sums over cells, so at 10x10 it is 4x what the same share of
    differing cells gives at 5x5: with the paper's v and threshold nearly every genome became a
    species of its own, each kept its elites, and the population grew past pop_size (the first
    10x10 SGR run: 15 species at generation 1, 1,335 and a population of 2,320 for pop_size 128 at
    generation 35). Scaled to the paper's 25 cells, the distance means at any size what it means at
    5x5, and the population stays at pop_size."""
    rows = _species_and_population(neat_config, (10, 10), 12)
    assert all(pop == 40 for _, pop in rows), rows
    assert max(n for n, _ in rows) <= 20, rows


def test_a_generations_build_s_is_the_time_its_genomes_took_to_decode(tmp_path, monkeypatch):
    """generations.csv's build_s (the console's "decode", issue 47 item 4) holds the decoding: with
    each decode slowed by 10 ms, the rows add up to 10 ms for each decode of their populations (the
    initial one in the first row; an elite is not decoded again), every generation of 8 genomes
    shows at least 4 (its offspring)."""
    import csv
    import time

    from evolve.methods.sgr import SgrProblem
    from evolve.runs.experiment import Experiment
    from tests.evolve.conftest import TINY

    real = SgrProblem.decode

    calls = []

    def slow(self, genome):
        calls.append(1)
        time.sleep(0.01)
        return real(self, genome)

    made_there = []  # the decodes made by a generation's decoding pass (the rest: the best's record)
    real_all = NeatSearch._decode_all

    def counted(self):
        before = len(calls)
        out = real_all(self)
        made_there.append(len(calls) - before)
        return out

    monkeypatch.setattr(SgrProblem, "decode", slow)
    monkeypatch.setattr(NeatSearch, "_decode_all", counted)
    cfg = {"method": "sgr", **TINY, "generations": 3}
    with Experiment.from_config(cfg, tmp_path / "run", quiet=True) as exp:
        exp.run_all()
    rows = list(csv.DictReader((tmp_path / "run" / "generations.csv").open()))
    assert len(rows) == 3
    for r in rows:  # (not compared with total_s: a row's decoding ran in the breeding that ended
        # the generation before, whose total_s counts it)
        assert float(r["build_s"]) >= 0.04, r
    # a generation's row holds the pass that decoded its population: the initial one, then the one
    # at the end of the generation before (its breeding); the last pass decodes the population of a
    # generation not run (a checkpoint keeps its time for a resumed run's next row)
    n = sum(made_there[:-1])
    assert n >= 8 + 2 * 4 and 0.01 * n <= sum(float(r["build_s"]) for r in rows) < 0.01 * n + 0.5
