"""What the run tests share: a tiny run of a method (2 generations of 8 genomes, 20-step episodes),
and the figures a test's plotting saves."""

from pathlib import Path

import pytest
from matplotlib.figure import Figure

from evolve.runs.experiment import Experiment

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
