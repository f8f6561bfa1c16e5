"""A run of a task registered in a script (docs/TASKS.md's step_left.py, no `imports:`) can be
used afterwards from other processes: the folder keeps a reference to the script (task.json: the
task's name, the script's path and sha256), never its code. With --trust-imports, `sgr render`,
`sgr report` and `sgr evolve --resume` import the script again (its run guarded by `if __name__ ==
"__main__"`); `load_champion` works in a process that imported the script itself. Without either,
each refuses in one line that says how to allow it, having run nothing of the script."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from evolve.records.rundir import RunDir

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

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

with open("executed.log", "a") as log:  # each time the script's code runs
    log.write(__name__ + "\\n")

if __name__ == "__main__":
    exp = Experiment.from_config({"method": "sgr", "task": "ScriptLeft-v0", "generations": 2,
                                  "pop_size": 8, "workers": 2, "render_champion": False,
                                  "robust": None, "final_selection": None}, out="runs/left")
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


def executed(cwd: Path) -> list[str]:
    """The names the script's code ran under, in order (its log)."""
    return (cwd / "executed.log").read_text().split()


def test_the_run_keeps_a_reference_to_the_script_not_its_code(script_run):
    ref = json.loads((script_run / "runs/left/task.json").read_text())
    script = script_run / "script.py"
    assert ref["task"] == "ScriptLeft-v0" and Path(ref["source"]) == script.resolve()
    assert ref["sha256"] == hashlib.sha256(script.read_bytes()).hexdigest()
    assert not (script_run / "runs/left/task.pkl").exists()


def test_a_script_task_run_renders_reports_loads_and_resumes_in_other_processes(script_run):
    cwd = script_run
    r = sgr("render", "runs/left", "--width", "64", "--height", "32", "--trust-imports", cwd=cwd)
    assert r.returncode == 0 and (cwd / "runs/left/champion.gif").is_file(), r.stderr
    r = sgr("report", "runs", "--replays", "1", "--no-gallery", "--trust-imports", cwd=cwd)
    assert r.returncode == 0 and "ScriptLeft-v0" in (cwd / "runs/report.md").read_text(), r.stderr
    code = ("import script; from evolve import load_champion; c = load_champion('runs/left'); "
            "print(c.task, c.rollout() == c.fitness)")
    r = run([sys.executable, "-c", code], cwd)
    assert r.returncode == 0 and r.stdout.split() == ["ScriptLeft-v0", "True"], r.stderr
    r = sgr("evolve", "--resume", "runs/left", "--generations", "3", "--workers", "2", "--quiet",
            "--trust-imports", cwd=cwd)
    assert r.returncode == 0, r.stderr
    assert [int(x["generation"]) for x in RunDir(cwd / "runs/left").rows()] == [1, 2, 3]
    assert executed(cwd)[0] == "__main__" and "__main__" not in executed(cwd)[1:]  # never ran again


def test_without_trust_a_script_task_is_refused_in_one_line_and_nothing_of_it_runs(script_run):
    before = executed(script_run)
    for args in (["render", "runs/left"], ["report", "runs/left", "--no-gallery"],
                 ["evolve", "--resume", "runs/left", "--generations", "9"]):
        r = sgr(*args, cwd=script_run)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2 and len(lines) == 1, r.stderr
        assert "task.json" in lines[0] and "script.py" in lines[0] and "--trust-imports" in lines[0], lines
    code = "from evolve import load_champion; load_champion('runs/left')"
    r = run([sys.executable, "-c", code], script_run)
    assert r.returncode == 1 and "--trust-imports" in r.stderr.strip().splitlines()[-1], r.stderr
    assert executed(script_run) == before
