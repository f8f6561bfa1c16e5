import random

import neat
import pytest
import yaml

from evolve.search.neat_ini import load_neat_config, neat_ini_text


@pytest.fixture()
def neat_config(tmp_path, repo_root):
    """The SGR neat config with the given pop size and CPPN outputs, as `sgr evolve` builds it."""
    def make(pop: int = 16, outputs: int = 1) -> neat.Config:
        ini = neat_ini_text(str(repo_root / "configs/neat/sgr.ini"), pop,
                            {"DefaultGenome": {"num_outputs": str(outputs)}})
        p = tmp_path / f"neat-{pop}-{outputs}.ini"
        p.write_text(ini)
        return load_neat_config(p)
    return make


@pytest.fixture()
def shipped_config(tmp_path, repo_root):
    """A shipped `configs/<method>/<task>.yaml` with `changes`, its neat ini paths made absolute,
    written to tmp_path (a tiny run of the real config)."""
    def make(method: str, task: str = "Walker-v0", **changes):
        raw = yaml.safe_load((repo_root / f"configs/{method}/{task}.yaml").read_text())
        raw.update(changes)
        for key in ("neat_config", "controller_neat_config"):
            if key in raw:
                raw[key] = str((repo_root / f"configs/{method}" / raw[key]).resolve())
        p = tmp_path / f"{method}-{task}.yaml"
        p.write_text(yaml.safe_dump(raw))
        return p
    return make


@pytest.fixture()
def genomes():
    """Fresh, then mutated, genomes of a neat config."""
    def make(config: neat.Config, n: int, mutations: int = 6, seed: int = 0) -> list:
        random.seed(seed)
        repro = neat.DefaultReproduction(config.reproduction_config, neat.reporting.ReporterSet(), None)
        gs = list(repro.create_new(config.genome_type, config.genome_config, n).values())
        for g in gs:
            for _ in range(mutations):
                g.mutate(config.genome_config)
        return gs
    return make
