"""Batched arbitrary-topology networks compute what neat-python's own networks compute."""

from types import SimpleNamespace

import neat
import numpy as np
import pytest

from evolve.nn.activations import NEAT_ACTIVATIONS
from evolve.nn.batch import NetworkBatch


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


def test_per_cell_queries_match_the_json_controller(neat_config, genomes):
    """The direct baseline's per_cell layout: each actuator is a query with its cell's (x, y) in
    inputs 0-1; the batched policy and the champion's JSON controller give the same actions."""
    from evolve.methods.sgr.substrates import cell_coordinates
    from evolve.nn.batch import GraphPolicy
    from evolve.nn.graph import GraphController

    cfg = neat_config(outputs=6)  # 7 inputs: (x, y) + a 5-long observation; 5 materials + 1 action
    gs = genomes(cfg, 4, mutations=8, seed=3)
    xy = cell_coordinates((5, 5))
    cells = [np.array([0, 6, 12, 24]), np.array([3]), np.array([7, 8, 9]), np.array([1, 2])]
    policy = GraphPolicy(NetworkBatch(gs, cfg.genome_config), cells, 4, 2, 5, cell_xy=xy)
    obs = np.random.default_rng(4).uniform(-1, 1, (4, 5))
    got = policy.act(obs)
    for b, g in enumerate(gs):
        ctrl = GraphController.from_json(GraphController.from_genome(
            g, cfg.genome_config, 5, 2, 5, cells[b], xy[cells[b]]).to_json())
        want = ctrl.act(obs[b])
        assert np.max(np.abs(got[b, :len(cells[b])] - want)) <= 1e-12
    assert np.ptp(got[0]) > 1e-6  # actuators at different cells get different actions


def test_a_network_computes_the_same_bits_alone_in_any_batch_and_from_its_json(neat_config, genomes):
    """A champion's JSON must replay its evolution episode exactly: a network's outputs may not
    depend on the batch it was evaluated in (padding), and the JSON controller's arithmetic is the
    batch's (each node's inputs summed one by one in slot order). With einsum, 3 of these 40
    networks differed alone and 6 from their JSON (by last bits)."""
    from evolve.nn.graph import GraphController

    cfg = neat_config(outputs=6)
    gs = genomes(cfg, 40, mutations=40, seed=5)
    for q in (1, 3):
        x = np.random.default_rng(q).uniform(-3, 3, (len(gs), q, 7))
        batch = NetworkBatch(gs, cfg.genome_config).forward(x)
        for b, g in enumerate(gs):
            assert np.array_equal(NetworkBatch([g], cfg.genome_config).forward(x[b:b + 1])[0], batch[b])
            ctrl = GraphController.from_json(GraphController.from_genome(
                g, cfg.genome_config, 7, 0, 0, np.arange(6)).to_json())
            assert np.array_equal(np.array([ctrl.outputs(row) for row in x[b]]), batch[b])


@pytest.mark.parametrize("activation", sorted(NEAT_ACTIVATIONS))
def test_the_json_controller_replays_the_batch_for_every_activation(activation):
    """One input, one output node of `activation` (z = the input): its JSON controller, one
    scalar at a time, gives the batch's bits for 10000 inputs. Two paper champions' JSON replays
    were off by 1e-16 and 5e-14 because gauss squared a scalar with C pow() (1 ulp off z * z for
    about 1 value in 1500) and an array with z * z."""
    from evolve.nn.graph import GraphController

    genome = neat.DefaultGenome(0)
    genome.nodes[0] = neat.genes.DefaultNodeGene(0)
    genome.nodes[0].bias, genome.nodes[0].response = 0.0, 1.0
    genome.nodes[0].activation, genome.nodes[0].aggregation = activation, "sum"
    link = neat.genes.DefaultConnectionGene((-1, 0), innovation=0)
    link.weight, link.enabled = 1.0, True
    genome.connections[(-1, 0)] = link
    config = SimpleNamespace(input_keys=[-1], output_keys=[0])
    x = np.random.default_rng(8).normal(0.0, 1.5, (1, 10_000, 1))
    batch = NetworkBatch([genome], config).forward(x)[0, :, 0]
    ctrl = GraphController.from_json(GraphController.from_genome(genome, config, 1, 0, 0, [0]).to_json())
    alone = np.array([ctrl.outputs(row)[0] for row in x[0]])
    assert np.array_equal(alone, batch)
