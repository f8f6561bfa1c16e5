"""A tasks.py, evolve.py and tsim.py in the working folder (invoke's tasks.py, say) replace none of
sgr's modules, in the `sgr` process or in the processes it starts (rollout workers, a sweep's runs):
each kind of process runs from such a folder, and (`-m long`) every `sgr` command of the README,
with tiny settings (`sgr validate`, 12 s, and `sgr demo` run in this process like `sgr bench`,
which stands for them). And where another
package of the same name comes first on the path, sgr uses its own and says so in one line."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# the `sgr` console script: like it, nothing of the working folder on sys.path (-P), sgr on PYTHONPATH
SGR = [sys.executable, "-P", "-c", "import sys; from evolve.cli import main; sys.exit(main())"]
SHADOWS = ("tasks", "evolve", "tsim", "parity")


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> tuple[Path, dict]:
    """A working folder whose tasks.py, evolve.py and tsim.py print when imported, and the env."""
    cwd = tmp_path_factory.mktemp("invoke-project")
    for name in SHADOWS:
        (cwd / f"{name}.py").write_text(f"print('IMPORTED THE FOLDER\\'S {name}.py')\n")
    (cwd / "tiny.yaml").write_text("method: sgr\ntask: Walker-v0\ngenerations: 2\npop_size: 8\n"
                                   "episode_steps: 20\nworkers: 2\n")
    (cwd / "sweep.yaml").write_text("methods: [sgr]\ntasks: [Walker-v0]\nseeds: 1\n"
                                    "overrides: {generations: 1, "
                                    "pop_size: 8, episode_steps: 20, render_champion: false}\n")
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    env["PYTHONPATH"] = str(ROOT)
    return cwd, env


def sgr(folder: tuple[Path, dict], *args: str) -> str:
    cwd, env = folder
    r = subprocess.run([*SGR, *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)
    out = r.stdout + r.stderr
    assert r.returncode == 0 and "IMPORTED THE FOLDER" not in out, f"sgr {' '.join(args)}:\n{out[-3000:]}"
    return out


@pytest.mark.slow
@pytest.mark.subprocess
def test_each_kind_of_sgr_process_runs_beside_a_tasks_py_an_evolve_py_and_a_tsim_py(folder):
    """The `sgr` process, its rollout workers (a run on two) and a sweep's run processes: none imports
    the folder's modules (every command of the README: the long test below)."""
    cwd, _ = folder
    sgr(folder, "evolve", "--config", "tiny.yaml", "--out", "short/tiny")
    sgr(folder, "sweep", "--config", "sweep.yaml", "--out", "short/sweep")
    assert (cwd / "short/tiny/champion.json").is_file()
    assert (cwd / "short/sweep/runs/sgr-Walker-v0-s0/champion.json").is_file()


@pytest.mark.long
@pytest.mark.slow
@pytest.mark.subprocess
def test_every_readme_command_runs_beside_a_tasks_py_an_evolve_py_and_a_tsim_py(folder):
    cwd, _ = folder
    run = re.search(r"run directory: (\S+)", sgr(folder, "evolve", "--config", "tiny.yaml")).group(1)
    sgr(folder, "evolve", "--resume", run, "--generations", "3")
    sgr(folder, "evolve", "--task", "Climber-v2", "--method", "direct", "--generations", "1", "--pop", "4",
        "--workers", "1", "--out", "runs/direct")  # (its workers are those of the tiny run's)
    sgr(folder, "plot", *sorted(str(p.relative_to(cwd)) for p in (cwd / "runs").iterdir()), "--per-run")
    sgr(folder, "render", run, "--width", "64", "--height", "32")
    sgr(folder, "render", run, "--replay", "1", "--width", "64", "--height", "32")
    sgr(folder, "select-champion", run, "--candidates", "2", "--episodes", "2", "--workers", "2")
    sgr(folder, "report", "runs", "--replays", "1", "--no-gallery")
    sgr(folder, "sweep", "--config", "sweep.yaml", "--out", "runs-paper/paper")
    sgr(folder, "sweep", "--resume", "runs-paper/paper")
    sgr(folder, "report", "runs-paper/paper", "--replays", "1", "--no-gallery")
    sgr(folder, "convert-checkpoints", run, "--trust-pickle")
    sgr(folder, "bench", "--robots", "2", "--steps", "5")
    assert (cwd / run / "champion.json").is_file() and (cwd / "runs-paper/paper/report.md").is_file()


def test_another_tasks_package_first_on_the_path_is_passed_over_with_one_line(tmp_path):
    """A folder on PYTHONPATH before sgr's holding a `tasks` package: `import evolve` still gets
    sgr's tasks, and one warning line names the other one and where it is."""
    other = tmp_path / "elsewhere" / "tasks"
    other.mkdir(parents=True)
    (other / "__init__.py").write_text("raise RuntimeError('the other tasks package was imported')\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(other.parent), str(ROOT)])}
    r = subprocess.run([sys.executable, "-P", "-c", "import evolve, tasks; print(tasks.__file__)"],
                       env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    assert Path(r.stdout.strip()) == ROOT / "tasks" / "__init__.py"
    lines = [line for line in r.stderr.splitlines() if line.startswith("sgr: warning")]
    assert len(lines) == 1 and str(other / "__init__.py") in lines[0] and "'tasks'" in lines[0], r.stderr
