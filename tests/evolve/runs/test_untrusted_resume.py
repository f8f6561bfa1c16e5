"""A resumed run's files are a stranger's: config.yaml and neat.ini planted with values no new run's
config may have (a checkpoint every 0 generations, a trillion-step episode, a list where a name
belongs, a population of a billion) are refused by `sgr evolve --resume` (and the other readers of
a folder) in one line naming the file and the key, before anything is run or rewritten; nothing
is deleted, nothing outside the folder changes (tests/evolve/attack.py)."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest
import yaml

from evolve.runs.experiment import Experiment
from tests.evolve.attack import Attack
from tests.evolve.conftest import unfinished_run

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def unfinished(tmp_path_factory) -> Path:
    """A tiny SGR run of 3 generations stopped after 2, checkpointed every generation: one to resume."""
    return unfinished_run(tmp_path_factory.mktemp("unfinished") / "run")


def plant(run: Path, file: str, key: str, value: str) -> None:
    """Set `key` of the run's `file` (config.yaml or neat.ini) to the text `value`, as a stranger
    editing the file would."""
    path = run / file
    if file == "config.yaml":
        raw = yaml.safe_load(path.read_text())
        assert key in raw, f"{key} not in {path}"
        path.write_text(yaml.safe_dump({**raw, key: yaml.safe_load(value)}, sort_keys=False))
        return
    new, n = re.subn(rf"(?m)^({re.escape(key)}[ ]*=[ ]*)\S.*$", lambda m: m.group(1) + value,
                     path.read_text(), count=1)
    assert n == 1, f"{key} not in {path}"
    path.write_text(new)


# (file, key, planted value, what the error line says of it)
PLANTED = [
    ("config.yaml", "checkpoint_every", "0", "must be >= 1, got 0"),
    ("config.yaml", "episode_steps", str(10**12), "must be at most 1,000,000"),
    ("config.yaml", "generations", "-1", "must be >= 1, got -1"),
    ("config.yaml", "generations", "many", "must be int, got 'many'"),
    ("config.yaml", "task", "[Walker-v0, Climber-v0]", "must be str"),
    ("config.yaml", "method", "[sgr]", "must be one of"),
    ("config.yaml", "pop_size", str(10**9), "must be at most 1,000,000"),
    ("config.yaml", "workers", str(10**9), "must be at most 4,096"),
    ("config.yaml", "robot_shape", "[100000, 100000]", "robot_shape"),
    ("config.yaml", "precision", "f128", "must be one of"),
    ("neat.ini", "pop_size", str(10**9), "must be an int from 1 to 1,000,000"),
    ("neat.ini", "pop_size", "0", "must be an int from 1 to 1,000,000, got 0"),
    ("neat.ini", "pop_size", "many", "must be an int, got 'many'"),
    ("neat.ini", "pop_size", "9", "config.yaml says 8"),
    ("neat.ini", "num_hidden", str(10**9), "must be an int from 0"),
    ("neat.ini", "num_outputs", "-3", "must be an int from 1"),
    ("neat.ini", "fitness_threshold", "a-lot", "must be a number"),
]


@pytest.mark.parametrize(("file", "key", "value", "says"), PLANTED,
                         ids=[f"{f}-{k}-{v[:12]}" for f, k, v, _ in PLANTED])
def test_a_planted_value_in_a_resumed_runs_file_is_one_line_naming_file_and_key(
        unfinished, tmp_path, capsys, file, key, value, says):
    """`sgr evolve --resume RUN` of a folder whose config.yaml or neat.ini holds a value no new
    run's config may have ends at once with one line naming the file and the key; the folder keeps
    every file, as it was."""
    attack = Attack(tmp_path)
    run = tmp_path / "run"
    shutil.copytree(unfinished, run)
    plant(run, file, key, value)
    before = {f: (run / f).read_bytes() for f in ("config.yaml", "neat.ini", "generations.csv")}
    with attack.watching(run):
        r = attack.main("evolve", "--resume", str(run), capsys=capsys, timeout=30)
    line = r.error_line()
    assert f"{run / file}: key {key!r}" in line and says in line, line
    assert r.seconds < 10, r.seconds
    assert {f: (run / f).read_bytes() for f in before} == before  # nothing rewritten


def test_a_planted_config_is_refused_before_generations_rewrites_it(unfinished, tmp_path, capsys):
    """`--resume RUN --generations 5` (which rewrites config.yaml with the new count) refuses a
    planted config.yaml first: the file is left as it was, not rewritten with the planted value."""
    attack = Attack(tmp_path)
    run = tmp_path / "run"
    shutil.copytree(unfinished, run)
    plant(run, "config.yaml", "checkpoint_every", "0")
    planted = (run / "config.yaml").read_bytes()
    with attack.watching(run):
        r = attack.main("evolve", "--resume", str(run), "--generations", "5", capsys=capsys)
    assert f"{run / 'config.yaml'}: key 'checkpoint_every' must be >= 1" in r.error_line()
    assert (run / "config.yaml").read_bytes() == planted


@pytest.mark.parametrize("command", [["select-champion"], ["decode", "--shape", "5x5"],
                                     ["render"]], ids=lambda c: c[0])
def test_the_other_readers_of_a_folder_check_its_config_too(unfinished, tmp_path, capsys, command):
    """select-champion, decode and render read a planted config.yaml's values only after the
    checks a new run's config gets: one line naming the file and the key."""
    attack = Attack(tmp_path)
    run = tmp_path / "run"
    shutil.copytree(unfinished, run)
    plant(run, "config.yaml", "episode_steps", str(10**12))
    with attack.watching(run):
        r = attack.main(command[0], str(run), *command[1:], capsys=capsys)
    line = r.error_line()
    assert f"{run / 'config.yaml'}: key 'episode_steps' must be at most" in line, line


def test_load_champion_checks_the_runs_config(unfinished, tmp_path):
    """evolve.load_champion of a folder with a planted config.yaml raises one SgrError naming it."""
    from evolve import load_champion
    from tsim.errors import SgrError

    run = tmp_path / "run"
    shutil.copytree(unfinished, run)
    plant(run, "config.yaml", "task", "[Walker-v0]")
    with pytest.raises(SgrError, match=re.escape(f"{run / 'config.yaml'}: key 'task' must be str")):
        load_champion(run)


def test_an_honest_run_still_resumes_to_its_end(unfinished, tmp_path, capsys):
    """The checks refuse nothing sgr writes: the unplanted copy resumes and finishes."""
    run = tmp_path / "run"
    shutil.copytree(unfinished, run)
    exp = Experiment.resume(run, quiet=True)
    with exp:
        exp.run_all()
    assert len(exp.run.rows()) == 3
