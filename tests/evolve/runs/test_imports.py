"""A task of one's own in configs and sweeps: `imports:` names the file that registers it, and
every sgr process of the run imports it (a fresh `sgr evolve`, its resume with --trust-imports, a
sweep's runs), with rollout workers that never import it. Read back from a run folder, the code
its config names is imported only with --trust-imports, whoever owns the files."""

import os
import subprocess
import sys

import pytest
import yaml

from evolve.records.rundir import RunDir

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

TASK_FILE = '''
import numpy as np
import tasks
from tasks import observations as O
from tsim import world_from_matrix

ground = np.zeros((8, 30), dtype=int)
ground[-1, :] = 5

def leftward(before, after):
    return before.com[:, 0] - after.com[:, 0]

tasks.register(tasks.TaskSpec(name="ImportedLeft-v0", world=world_from_matrix(ground), origin=(20, 1),
                              paper_steps=20, evogym_steps=20, observation=(O.VCOM, O.POINTS),
                              reward=leftward))
'''
RUN = {"method": "sgr", "task": "ImportedLeft-v0", "generations": 2, "pop_size": 8, "workers": 2,
       "render_champion": False, "imports": ["my_tasks.py"], "robust": None, "final_selection": None}


def sgr(*args, cwd) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    return subprocess.run([sys.executable, "-m", "evolve.cli", *args], cwd=cwd, capture_output=True,
                          text=True, env=env, timeout=300)


def test_a_config_and_a_sweep_run_a_task_registered_in_an_imported_file(tmp_path):
    (tmp_path / "conf").mkdir()
    (tmp_path / "conf" / "my_tasks.py").write_text(TASK_FILE)
    (tmp_path / "conf" / "run.yaml").write_text(yaml.safe_dump(RUN))
    r = sgr("evolve", "--config", "conf/run.yaml", "--out", "r", "--quiet", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    run = RunDir(tmp_path / "r")
    assert run.config()["imports"] == [str(tmp_path / "conf" / "my_tasks.py")]  # relative to the config
    assert run.config()["episode_steps"] == 20 and len(run.rows()) == 2
    r = sgr("evolve", "--resume", "r", "--generations", "3", "--quiet", "--trust-imports", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert [int(x["generation"]) for x in run.rows()] == [1, 2, 3]

    overrides = {k: v for k, v in RUN.items() if k not in ("method", "task", "imports")}
    (tmp_path / "conf" / "configs" / "sgr").mkdir(parents=True)
    (tmp_path / "conf" / "configs" / "sgr" / "ImportedLeft-v0.yaml").write_text(
        yaml.safe_dump({"method": "sgr", "task": "ImportedLeft-v0"}))
    (tmp_path / "conf" / "sweep.yaml").write_text(yaml.safe_dump(
        {"methods": ["sgr"], "tasks": ["ImportedLeft-v0"], "seeds": 1, "configs": "configs",
         "imports": ["my_tasks.py"], "overrides": overrides}))
    r = sgr("sweep", "--config", "conf/sweep.yaml", "--out", "s", "--quiet", cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert len(RunDir(tmp_path / "s" / "runs" / "sgr-ImportedLeft-v0-s0").rows()) == 2


def test_an_imports_entry_that_fails_names_the_config_and_the_file(tmp_path):
    (tmp_path / "run.yaml").write_text(yaml.safe_dump({**RUN, "imports": ["missing.py"]}))
    r = sgr("evolve", "--config", "run.yaml", "--out", "r", cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "run.yaml: key 'imports'" in r.stderr and "missing.py" in r.stderr


def test_code_named_by_a_run_folder_runs_only_with_trust_imports_even_in_ones_own_folder(tmp_path):
    """Starting a run from a config imports the code it names (the user named the config);
    resuming, reporting or rendering the run folder afterwards does not, even where the user owns
    every file (ownership says nothing about a folder one extracted or copied): one line names the
    config and --trust-imports, and nothing of the code runs."""
    marker = tmp_path / "ran"
    (tmp_path / "my_tasks.py").write_text(TASK_FILE + f"\nopen({str(marker)!r}, 'a').close()\n")
    os.chmod(tmp_path / "my_tasks.py", 0o600)  # yours alone
    (tmp_path / "run.yaml").write_text(yaml.safe_dump({**RUN, "workers": 1}))
    assert sgr("evolve", "--config", "run.yaml", "--out", "r", "--quiet", cwd=tmp_path).returncode == 0
    assert marker.exists()  # the user named the config: its code ran
    marker.unlink()
    for args in (("evolve", "--resume", "r", "--generations", "4", "--quiet"),
                 ("render", "r", "--out", "c.gif"), ("report", ".", "--replays", "1", "--no-gallery")):
        r = sgr(*args, cwd=tmp_path)
        assert r.returncode == 2 and r.stderr.count("\n") == 1, (args, r.stderr)
        assert "r/config.yaml names code to import" in r.stderr and "--trust-imports" in r.stderr, r.stderr
        assert not marker.exists(), args
    assert len(RunDir(tmp_path / "r").rows()) == 2
    r = sgr("evolve", "--resume", "r", "--generations", "3", "--quiet", "--trust-imports", cwd=tmp_path)
    assert r.returncode == 0 and marker.exists(), r.stderr
    assert len(RunDir(tmp_path / "r").rows()) == 3
