"""neat-python classes we extend: a genome whose speciation distance adds the body distance
(SGR paper eq. 1), a reproduction that survives more species than the population can hold, and
a genome config that can be pickled without side effects.

distance = NEAT genomic distance + v * scaled_body_distance(body, body') (eq. 2, scaled to 5x5).
The bodies come from a cache the search fills (by genome key) before every speciation, so no
genome is decoded twice.
"""

from __future__ import annotations

from itertools import count

import neat.genome
from neat import DefaultGenome, DefaultReproduction
from neat.genes import DefaultConnectionGene, DefaultNodeGene
from neat.genome import DefaultGenomeConfig
from neat.graphs import creates_cycle

from evolve.search.body_distance import scaled_body_distance


def _creates_cycle(connections, test) -> bool:
    """neat-python's check, answered at once for links leaving an input node (inputs have negative
    keys and never receive links, so no path can lead back to them). Exact, and it turns
    neat-python 2's crossover from quadratic to ~linear for the baselines' wide input layers."""
    return False if test[0] < 0 else creates_cycle(connections, test)


neat.genome.creates_cycle = _creates_cycle  # used by DefaultGenome.configure_crossover


def peek(counter: count | None) -> tuple[int | None, count | None]:
    """The next value of an `itertools.count` without consuming it: (value, counter to keep)."""
    if counter is None:
        return None, None
    nxt = next(counter)
    return nxt, count(nxt)


class GenomeConfig(DefaultGenomeConfig):
    """neat-python 2 pickles a genome config by consuming one node key from its `node_indexer`, so
    every pickle (a checkpoint, a batch of networks sent to a rollout worker) changed the keys of
    later nodes. Here pickling leaves the counter as it was, and the speciation body cache (only
    needed where speciation runs) stays behind."""

    def __getstate__(self):
        nxt, self.node_indexer = peek(self.node_indexer)
        state = {k: v for k, v in self.__dict__.items() if k != "body_cache"}
        state.update(node_indexer=None, _node_indexer_next_value=nxt)
        return state

    def __setstate__(self, state):
        super().__setstate__(state)
        self.body_cache = {}


class BodyAwareGenome(DefaultGenome):
    """neat-python's DefaultGenome whose speciation distance adds body_distance_weight x body
    distance (eq. 1), with the bodies from the config's body_cache."""
    @classmethod
    def parse_config(cls, param_dict):
        """Default gene types, but a `GenomeConfig`, which pickles without consuming a node key."""
        param_dict["node_gene_type"] = DefaultNodeGene
        param_dict["connection_gene_type"] = DefaultConnectionGene
        return GenomeConfig(param_dict, cls.__name__)

    def distance(self, other, config) -> float:
        """NEAT distance + body_distance_weight x body distance, the body distance scaled to the
        paper's 5x5 bodies (`scaled_body_distance`); with a non-zero weight both genomes' bodies
        must be in config.body_cache (KeyError otherwise)."""
        d = super().distance(other, config)
        v = getattr(config, "body_distance_weight", 0.0)
        if v:
            bodies = config.body_cache
            d += v * scaled_body_distance(bodies[self.key], bodies[other.key])
        return d


class FlexibleReproduction(DefaultReproduction):
    """neat-python 2's reproduction with a total-preserving spawn adjustment that cannot fail:
    largest species shrink first, smallest grow first, and when there are more species than
    pop_size / min_species_size the per-species minimum is lowered for that generation instead
    of aborting the run (neat-python 2.0 raises there, and also gives up after one pass)."""

    def _adjust_spawn_exact(self, spawn_amounts, pop_size, min_species_size):
        floor = max(1, min(min_species_size, pop_size // max(1, len(spawn_amounts))))
        spawn = [max(floor, int(s)) for s in spawn_amounts]
        while sum(spawn) > pop_size:
            i = max(range(len(spawn)), key=lambda j: (spawn[j], -j))
            if spawn[i] <= floor:
                break
            spawn[i] -= 1
        while sum(spawn) < pop_size:
            spawn[min(range(len(spawn)), key=lambda j: (spawn[j], j))] += 1
        return spawn
