"""What the evolve tests share: neat configs and shipped configs made for a test, a tiny run of a
method (2 generations of 8 genomes, 20-step episodes) and an unfinished one, and the figures a
test's plotting saves."""

import random
from pathlib import Path

import neat
import pytest
import yaml
from matplotlib.figure import Figure

from evolve.runs.experiment import Experiment
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


TINY = {"task": "Walker-v0", "generations": 2, "pop_size": 8, "seed": 3, "episode_steps": 20,
        "workers": 1, "render_champion": False, "robust": None, "final_selection": None}


def tiny_run(method: str, folder: Path) -> Path:
    """Run `method` with the TINY settings into `folder` and return it."""
    with Experiment.from_config({"method": method, **TINY}, folder, quiet=True) as exp:
        exp.run_all()
    return folder


class _Stop(Exception):
    """Ends a tiny run early (`unfinished_run`)."""


def unfinished_run(folder: Path) -> Path:
    """A tiny SGR run of 3 generations stopped after 2, checkpointed every generation (checkpoints
    after 1 and 2, a champion): one to resume. Returns `folder`."""
    def stop_after_two(exp: Experiment) -> None:
        if exp.search.generation >= 2:
            raise _Stop

    with Experiment.from_config({"method": "sgr", **TINY, "generations": 3, "checkpoint_every": 1},
                                folder, quiet=True) as exp:
        with pytest.raises(_Stop):
            exp.run_all(stop_after_two)
    return folder


@pytest.fixture(scope="module")
def sgr_run(tmp_path_factory) -> Path:
    """A finished tiny SGR run, once per test file."""
    return tiny_run("sgr", tmp_path_factory.mktemp("tiny") / "sgr")


@pytest.fixture
def saved(monkeypatch) -> list[Figure]:
    """The figures saved as PNGs during the test, in order."""
    figs: list[Figure] = []
    real = Figure.savefig

    def spy(self, *a, **k):
        figs.append(self)
        return real(self, *a, **k)
    monkeypatch.setattr(Figure, "savefig", spy)
    return figs
