"""A run of a task registered in a script (docs/TASKS.md's step_left.py, no `imports:`) can be
used afterwards from other processes: it renders, reports, resumes and loads with
`load_champion`. The folder keeps the task's code; where someone else could have written it, each
of those refuses in one line that says how to allow it (--trust-imports), as `imports:` does."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from evolve.runs.rundir import RunDir

ROOT = Path(__file__).resolve().parents[3]

SCRIPT = '''
import numpy as np
import tasks
from evolve import Experiment
from tasks import Measure, TaskSpec
from tasks import observations as O
from tsim import world_from_matrix

ground = np.zeros((9, 40), dtype=int)
ground[-2:, :] = 5
ground[-3, 26:] = 5


def leftward(before: Measure, after: Measure):
    return before.com[:, 0] - after.com[:, 0]


tasks.register(TaskSpec(name="ScriptLeft-v0", world=world_from_matrix(ground), origin=(30, 3),
                        paper_steps=20, evogym_steps=20, observation=(O.VCOM, O.POINTS),
                        reward=leftward, goal=(20, 1.0, "left")))

exp = Experiment.from_config({"method": "sgr", "task": "ScriptLeft-v0", "generations": 2,
                              "pop_size": 8, "workers": 2, "render_champion": False}, out="runs/left")
exp.run_all()
exp.finish()
'''


def run(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    env["PYTHONPATH"] = str(ROOT)  # this sgr, not whichever one is installed
    return subprocess.run(args, cwd=cwd, capture_output=True, text=True, env=env, timeout=300)


def sgr(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return run([sys.executable, "-m", "evolve.cli", *args], cwd)


@pytest.fixture(scope="module")
def script_run(tmp_path_factory) -> Path:
    """The folder in which step_left-like script.py left runs/left (2 generations)."""
    cwd = tmp_path_factory.mktemp("script-task")
    (cwd / "script.py").write_text(SCRIPT)
    r = run([sys.executable, "script.py"], cwd)
    assert r.returncode == 0, r.stderr[-3000:]
    return cwd


def test_a_script_task_run_renders_reports_loads_and_resumes_in_other_processes(script_run):
    cwd = script_run
    r = sgr("render", "runs/left", "--width", "64", "--height", "32", cwd=cwd)
    assert r.returncode == 0 and (cwd / "runs/left/champion.gif").is_file(), r.stderr
    r = sgr("report", "runs", "--replays", "1", "--no-gallery", cwd=cwd)
    assert r.returncode == 0 and "ScriptLeft-v0" in (cwd / "runs/report.md").read_text(), r.stderr
    code = ("from evolve import load_champion; c = load_champion('runs/left'); "
            "print(c.task, c.rollout() == c.fitness)")
    r = run([sys.executable, "-c", code], cwd)
    assert r.returncode == 0 and r.stdout.split() == ["ScriptLeft-v0", "True"], r.stderr
    r = sgr("evolve", "--resume", "runs/left", "--generations", "3", "--workers", "2", "--quiet", cwd=cwd)
    assert r.returncode == 0, r.stderr
    assert [int(x["generation"]) for x in RunDir(cwd / "runs/left").rows()] == [1, 2, 3]


def test_a_script_task_others_could_write_is_refused_in_one_line_naming_trust_imports(script_run):
    task_file = script_run / "runs/left/task.pkl"
    mode = task_file.stat().st_mode
    task_file.chmod(mode | stat.S_IWGRP)
    try:
        for args in (["render", "runs/left"], ["report", "runs/left", "--no-gallery"],
                     ["evolve", "--resume", "runs/left", "--generations", "9"]):
            r = sgr(*args, cwd=script_run)
            lines = r.stderr.strip().splitlines()
            assert r.returncode == 2 and len(lines) == 1, r.stderr
            assert "task.pkl" in lines[0] and "--trust-imports" in lines[0], lines
        r = sgr("render", "runs/left", "--width", "64", "--height", "32", "--out", "trusted.gif",
                "--trust-imports", cwd=script_run)
        assert r.returncode == 0 and (script_run / "trusted.gif").is_file(), r.stderr
    finally:
        task_file.chmod(mode)
