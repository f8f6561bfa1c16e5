"""The NEAT loop: invalid bodies are counted and never simulated; speciation adds v x body distance."""

import neat
import numpy as np

from evolve.body_distance import body_distance
from evolve.neat_search import NeatSearch
from evolve.sgr_decoder import DecoderSettings, decode, is_valid_robot


def test_invalid_bodies_are_counted_excluded_from_simulation_and_from_the_population(neat_config):
    cfg = neat_config(pop=40)
    seen = []

    def evaluate(phenotypes):
        seen.extend(phenotypes)
        return np.array([float(np.count_nonzero(p.body)) for p in phenotypes])  # cheap stand-in fitness

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


def test_speciation_distance_adds_v_times_the_body_distance(neat_config, genomes):
    cfg = neat_config()
    gc = cfg.genome_config
    a, b = genomes(cfg, 2, mutations=3)
    base = neat.DefaultGenome.distance(a, b, gc)
    gc.body_cache = {a.key: np.array([[1, 2], [3, 0]]), b.key: np.array([[2, 2], [0, 0]])}
    gc.body_distance_weight = 0.25
    assert a.distance(b, gc) == base + 0.25 * body_distance(gc.body_cache[a.key], gc.body_cache[b.key])
    gc.body_distance_weight = 0.0
    assert a.distance(b, gc) == base
