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


def test_asking_for_some_output_columns_gives_those_columns_of_the_full_pass_bit_for_bit(ini):
    """`cppn(x, columns)` computes only the nodes those outputs depend on (a hidden node that feeds
    only another output is skipped), and the numbers are the full pass's, bit for bit."""
    cfg = _config(5, ini)
    gc = cfg.genome_config
    random.seed(11)
    repro = neat.DefaultReproduction(cfg.reproduction_config, neat.reporting.ReporterSet(), None)
    genomes = list(repro.create_new(cfg.genome_type, gc, 8).values())
    for i, g in enumerate(genomes):
        for _ in range(3 * i):
            g.mutate(gc)
    x = np.random.default_rng(1).uniform(-1.5, 1.5, (30, 7))
    skipped = 0
    for g in genomes:
        cppn = CompiledCPPN(g, gc)
        full = cppn(x)
        for cols in [(0,), (4,), (1, 2, 3, 4), (3, 0)]:
            assert np.array_equal(cppn(x, cols), full[:, list(cols)])
            skipped += len(cppn.steps) - len(cppn.needed(cols) & {s[0] for s in cppn.steps})
    assert skipped > 0
