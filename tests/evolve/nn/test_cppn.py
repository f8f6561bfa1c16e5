"""The compiled CPPN computes exactly what neat-python's own network computes."""

import random

import neat
import numpy as np
import pytest

from evolve.nn.cppn import CompiledCPPN


def _config(n_out: int, ini) -> neat.Config:
    return neat.Config(neat.DefaultGenome, neat.DefaultReproduction, neat.DefaultSpeciesSet,
                       neat.DefaultStagnation, ini(n_out))


@pytest.fixture()
def ini(tmp_path, repo_root):
    def make(n_out: int):
        text = (repo_root / "configs/neat/sgr.ini").read_text()
        text = text.replace("num_outputs             = 1", f"num_outputs             = {n_out}")
        text = text.replace("activation_options      = sin tanh gauss",
                            "activation_options      = sin tanh gauss sigmoid identity abs")
        p = tmp_path / f"cppn{n_out}.ini"
        p.write_text(text)
        return str(p)
    return make


@pytest.mark.parametrize("n_out", [1, 2])
def test_vectorized_cppn_equals_neat_python_activate(n_out, ini):
    cfg = _config(n_out, ini)
    gc = cfg.genome_config
    random.seed(n_out)
    repro = neat.DefaultReproduction(cfg.reproduction_config, neat.reporting.ReporterSet(), None)
    genomes = list(repro.create_new(cfg.genome_type, gc, 6).values())
    for i, g in enumerate(genomes):
        for _ in range(4 * i):  # grow hidden nodes, change activations, disable links
            g.mutate(gc)
    assert any(len(g.nodes) > n_out for g in genomes)
    x = np.random.default_rng(0).uniform(-1.5, 1.5, (40, 7))
    for g in genomes:
        net = neat.nn.FeedForwardNetwork.create(g, cfg)
        ref = np.array([net.activate(row) for row in x])
        got = CompiledCPPN(g, gc)(x)
        assert got.shape == (40, n_out)
        assert np.max(np.abs(got - ref)) <= 1e-12


def test_wrong_input_width_is_rejected(ini):
    cfg = _config(1, ini)
    g = neat.DefaultReproduction(cfg.reproduction_config, neat.reporting.ReporterSet(), None) \
        .create_new(cfg.genome_type, cfg.genome_config, 1)
    with pytest.raises(ValueError, match="CPPN expects"):
        CompiledCPPN(next(iter(g.values())), cfg.genome_config)(np.zeros((3, 6)))
