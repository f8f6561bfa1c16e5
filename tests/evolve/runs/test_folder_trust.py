"""A run folder received from someone else runs nothing by being read (docs/RELIABILITY.md "Trust").

A `task.pkl` planted in a copied run folder, or a module planted beside it and named by its
config's `imports:`, would create a marker file if it ran: `sgr render`, `sgr report`, `sgr evolve
--resume` and `load_champion` leave no marker, and each refuses in one line that names the file
and says how to trust it. With --trust-imports the imports run and the run works; registering the
task in one's own process works without reading anything; a reference whose source changed, or is
gone, is refused; an older sgr's task.pkl converts (with --trust-pickle) into a reference."""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import shutil
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml

from evolve.cli import main
from evolve.records.replay import load_champion
from evolve.records.rundir import RunDir
from evolve.runs.experiment import Experiment
from tasks import Measure, TaskSpec, register
from tasks import observations as O
from tasks.specs import TASKS, forget_worlds
from tsim import world_from_matrix
from tsim.errors import SgrError

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

ROOT = Path(__file__).resolve().parents[3]
NAME = "FolderLeft-v0"

GROUND = np.zeros((8, 30), dtype=int)
GROUND[-1, :] = 5


def leftward(before: Measure, after: Measure):
    return before.com[:, 0] - after.com[:, 0]


def spec() -> TaskSpec:
    return TaskSpec(name=NAME, world=world_from_matrix(GROUND), origin=(20, 1), paper_steps=20,
                    evogym_steps=20, observation=(O.VCOM, O.POINTS), reward=leftward)


# the module a planted config names: it would register the task, and leaves a marker when it runs
PLANTED_MODULE = '''
import numpy as np
import tasks
from tasks import observations as O
from tsim import world_from_matrix

open({marker!r}, "a").close()
ground = np.zeros((8, 30), dtype=int)
ground[-1, :] = 5

def leftward(before, after):
    return before.com[:, 0] - after.com[:, 0]

tasks.register(tasks.TaskSpec(name={name!r}, world=world_from_matrix(ground), origin=(20, 1),
                              paper_steps=20, evogym_steps=20, observation=(O.VCOM, O.POINTS),
                              reward=leftward))
'''


class _Payload:
    """Unpickling this creates `path` (a pickle runs what its author chose)."""

    def __init__(self, path: Path):
        self.path = str(path)

    def __reduce__(self):
        return open, (self.path, "a")


def _forget_task() -> None:
    TASKS.pop(NAME, None)
    forget_worlds()
    gym.registry.pop(f"sgr/{NAME}", None)


@pytest.fixture
def registered_here():
    """The task registered in this process for the test, as a user's script does."""
    register(spec(), replace=True)
    yield
    _forget_task()


@pytest.fixture(scope="module")
def base(tmp_path_factory) -> Path:
    """A finished one-generation run of a task registered here (its folder keeps task.json)."""
    folder = tmp_path_factory.mktemp("folder-trust")
    register(spec(), replace=True)
    try:
        cfg = {"method": "sgr", "task": NAME, "generations": 1, "pop_size": 8, "workers": 1,
               "render_champion": False, "robust": None, "final_selection": None}
        with Experiment.from_config(cfg, folder / "run", quiet=True) as exp:
            exp.run_all()
    finally:
        _forget_task()
    return folder / "run"


def copied(base: Path, where: Path) -> Path:
    """The run folder as received from someone else: copied, its task reference dropped."""
    out = where / "received"
    shutil.copytree(base, out)
    (out / "task.json").unlink()
    return out


def sgr(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    env["PYTHONPATH"] = str(ROOT)
    return subprocess.run([sys.executable, "-m", "evolve.cli", *args], cwd=cwd, capture_output=True,
                          text=True, env=env, timeout=300)


READERS = (("render", "received", "--width", "32", "--height", "16", "--out", "c.gif"),
           ("report", "received", "--replays", "1", "--no-gallery"),
           ("evolve", "--resume", "received", "--generations", "2", "--quiet"))


def test_the_run_keeps_its_task_as_a_reference_to_this_file_with_its_digest(base):
    ref = json.loads((base / "task.json").read_text())
    assert ref["task"] == NAME and Path(ref["source"]) == Path(__file__).resolve()
    assert ref["sha256"] == hashlib.sha256(Path(__file__).read_bytes()).hexdigest()
    assert not (base / "task.pkl").exists()


def test_a_planted_task_pkl_runs_nothing_and_each_reader_says_how_to_convert_it(base, tmp_path):
    run = copied(base, tmp_path)
    marker = tmp_path / "ran"
    (run / "task.pkl").write_bytes(pickle.dumps(_Payload(marker)))
    for args in READERS + tuple((*a, "--trust-imports") for a in READERS[:1]):
        r = sgr(*args, cwd=tmp_path)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2 and len(lines) == 1, (args, r.stderr)
        assert "task.pkl" in lines[0] and "sgr migrate" in lines[0] \
            and "--trust-pickle" in lines[0], lines
        assert not marker.exists(), args
    with pytest.raises(SgrError) as err:
        load_champion(run)
    assert "task.pkl" in str(err.value) and "\n" not in str(err.value)
    assert not marker.exists()
    assert len(RunDir(run).rows()) == 1  # the resume did not start


def test_a_planted_module_named_by_imports_runs_only_with_trust_imports(base, tmp_path):
    run = copied(base, tmp_path)
    marker = tmp_path / "ran"
    (run / "evil.py").write_text(PLANTED_MODULE.format(marker=str(marker), name=NAME))
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    (run / "config.yaml").write_text(yaml.safe_dump({**cfg, "imports": [str(run / "evil.py")]},
                                                    sort_keys=False))
    for args in READERS:
        r = sgr(*args, cwd=tmp_path)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2 and len(lines) == 1, (args, r.stderr)
        assert "config.yaml names code to import" in lines[0] and "evil.py" in lines[0] \
            and "--trust-imports" in lines[0], lines
        assert not marker.exists(), args
    with pytest.raises(SgrError) as err:
        load_champion(run)
    assert "--trust-imports" in str(err.value) and "\n" not in str(err.value)
    assert not marker.exists() and len(RunDir(run).rows()) == 1

    r = sgr("evolve", "--resume", "received", "--generations", "2", "--quiet", "--trust-imports",
            cwd=tmp_path)
    assert r.returncode == 0 and marker.exists(), r.stderr  # trusted: its code ran, the run went on
    assert len(RunDir(run).rows()) == 2
    marker.unlink()
    r = sgr(*READERS[0], "--trust-imports", cwd=tmp_path)
    assert r.returncode == 0 and marker.exists() and (tmp_path / "c.gif").is_file(), r.stderr


def test_a_task_registered_in_ones_own_process_loads_without_reading_the_folders_code(
        base, tmp_path, registered_here):
    run = copied(base, tmp_path)
    marker = tmp_path / "ran"
    (run / "task.pkl").write_bytes(pickle.dumps(_Payload(marker)))
    (run / "evil.py").write_text(PLANTED_MODULE.format(marker=str(marker), name=NAME))
    champ = load_champion(run)
    assert champ.task == NAME and champ.rollout() == champ.fitness
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    (run / "config.yaml").write_text(yaml.safe_dump({**cfg, "imports": [str(run / "evil.py")]},
                                                    sort_keys=False))
    assert load_champion(run).task == NAME
    assert not marker.exists()


@pytest.mark.parametrize("change", ["digest", "missing"])
def test_a_reference_whose_source_changed_or_is_gone_is_refused_even_when_trusted(base, tmp_path, change):
    run = tmp_path / "received"
    shutil.copytree(base, run)
    ref = json.loads((run / "task.json").read_text())
    if change == "digest":
        ref["sha256"] = hashlib.sha256(b"another file").hexdigest()
    else:
        ref["source"] = str(tmp_path / "gone.py")
    (run / "task.json").write_text(json.dumps(ref))
    r = sgr(*READERS[0], "--trust-imports", cwd=tmp_path)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1, r.stderr
    assert "task.json" in lines[0] and ("has changed" if change == "digest" else "not there") in lines[0]
    assert not (tmp_path / "c.gif").exists()


def test_an_older_task_pkl_converts_with_trust_pickle_into_a_reference(base, tmp_path, registered_here):
    """An older sgr's task.pkl (the spec pickled as rollout workers get it) becomes task.json, its
    source the file the reward was written in; the run then reads as any other."""
    from evolve.rollout.worker import spec_blob

    run = copied(base, tmp_path)
    (run / "task.pkl").write_bytes(spec_blob(NAME))
    _forget_task()
    assert main(["convert-checkpoints", str(run), "--trust-pickle"]) == 0
    ref = json.loads((run / "task.json").read_text())
    assert ref["task"] == NAME and Path(ref["source"]) == Path(__file__).resolve()
    assert ref["sha256"] == hashlib.sha256(Path(__file__).read_bytes()).hexdigest()
    assert not (run / "task.pkl").exists() and NAME in TASKS
    assert load_champion(run).task == NAME


def test_a_sweep_folder_naming_planted_code_runs_none_of_it(tmp_path):
    """`sgr sweep --resume` reads sweep.yaml back: its imports are refused in one line when its
    tasks need them, and not imported at all when they do not (sgr's own tasks), as its runs are
    created."""
    from evolve.sweeps.sweep import Sweep

    marker = tmp_path / "ran"
    sw = tmp_path / "sw"
    (sw / "runs").mkdir(parents=True)
    (sw / "evil.py").write_text(PLANTED_MODULE.format(marker=str(marker), name=NAME))
    for task in (NAME, "Walker-v0"):
        (tmp_path / "configs" / "sgr" / f"{task}.yaml").parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / "configs" / "sgr" / f"{task}.yaml").write_text(yaml.safe_dump(
            {"method": "sgr", "task": task, "generations": 1, "pop_size": 8, "workers": 1,
             "render_champion": False, "robust": None, "final_selection": None}))
    sweep = {"methods": ["sgr"], "tasks": [NAME], "seeds": [0], "configs": str(tmp_path / "configs"),
             "overrides": {}, "imports": [str(sw / "evil.py")]}
    (sw / "sweep.yaml").write_text(yaml.safe_dump(sweep))
    with pytest.raises(SgrError) as err:
        Sweep.open(sw)
    assert "sweep.yaml names code to import" in str(err.value) and "--trust-imports" in str(err.value)
    assert "\n" not in str(err.value) and not marker.exists()

    (sw / "sweep.yaml").write_text(yaml.safe_dump({**sweep, "tasks": ["Walker-v0"]}))
    opened = Sweep.open(sw)
    opened.prepare(opened.runs[0])
    assert opened.run_dir(opened.runs[0]).has_checkpoint() and not marker.exists()


def test_trust_imports_given_to_one_in_process_command_ends_with_it(tmp_path):
    """`main([..., "--trust-imports"])` called from Python (a notebook, a test) trusts the folders
    of that command only: the process trusts nothing afterwards, even when the command failed."""
    from tasks.registry import imports_trusted

    assert not imports_trusted()
    assert main(["report", str(tmp_path / "nothing-here"), "--trust-imports"]) == 2
    assert not imports_trusted()
