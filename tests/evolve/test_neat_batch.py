"""Batched arbitrary-topology networks compute what neat-python's own networks compute."""

import neat
import numpy as np

from evolve.neat_batch import NetworkBatch


def test_batched_networks_equal_neat_python_activate(neat_config, genomes):
    cfg = neat_config()
    gs = genomes(cfg, 10, mutations=12)
    assert len({len(g.nodes) for g in gs}) > 1  # different topologies and depths in one batch
    x = np.random.default_rng(2).uniform(-1, 1, (len(gs), 5, 7))
    got = NetworkBatch(gs, cfg.genome_config).forward(x)
    for b, g in enumerate(gs):
        net = neat.nn.FeedForwardNetwork.create(g, cfg)
        ref = np.array([net.activate(row) for row in x[b]])
        assert np.max(np.abs(got[b] - ref)) <= 1e-12
