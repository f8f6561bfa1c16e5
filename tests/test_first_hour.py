"""A researcher's first hour, as docs/FIRST_HOUR.md (and the README) and docs/TASKS.md tell it,
from a folder outside the repository with sgr installed non-editably (`pip install --target`, no
dependencies: they come from this environment). Slow-ish (~1 min): it builds the package and
runs three real processes."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def code_block(doc: Path, heading: str) -> str:
    """The first ```python block after `heading` in `doc`."""
    text = doc.read_text()
    return re.search(r"```python\n(.*?)```", text[text.index(heading):], re.S).group(1)


FIRST_HOUR = ROOT / "docs" / "FIRST_HOUR.md"


def test_readme_first_hour_reads_in_order():
    text = FIRST_HOUR.read_text()
    steps = ["**1. Install**", "**2. Run**", "**3. Look**", "**4. Use your champion**",
             "**5. Your own task**"]
    where = [text.find(s) for s in steps]
    assert -1 not in where and where == sorted(where) and where[-1] < text.find("## What is here")
    snippet = code_block(FIRST_HOUR, "**4. Use your champion**").strip().splitlines()
    assert snippet[0].startswith("from evolve import") and len(snippet) == 6  # an import, five lines


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(site folder, a folder outside the repository, the environment that runs the installed copy)."""
    tmp = tmp_path_factory.mktemp("first-hour")
    site = tmp / "site"
    build = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation",
                            "--target", str(site), str(ROOT)], capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    elsewhere = tmp / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    env["PYTHONPATH"] = str(site)
    return site, elsewhere, env


def run(args, installed, timeout=300) -> subprocess.CompletedProcess:
    _, elsewhere, env = installed
    r = subprocess.run(args, cwd=elsewhere, env=env, capture_output=True, text=True, timeout=timeout)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-3000:]
    return r


@pytest.mark.slow
@pytest.mark.subprocess
def test_evolve_a_task_then_use_the_champion_as_the_readme_says(installed):
    site, elsewhere, _ = installed
    r = run([str(site / "bin" / "sgr"), "evolve", "--task", "Climber-v2", "--generations", "2"], installed)
    run_dir = re.search(r"run directory: (\S+)", r.stdout).group(1)
    assert run_dir.startswith("runs/sgr-Climber-v2-seed0-")
    where = run([sys.executable, "-c", "import evolve; print(evolve.__file__)"], installed).stdout
    assert where.startswith(str(site)), where  # the installed copy, not the repository
    snippet = code_block(FIRST_HOUR, "**4. Use your champion**")
    assert snippet in (ROOT / "README.md").read_text()  # the README shows the same lines
    snippet = snippet.replace("runs/sgr-quick-seed0-<time>", run_dir)
    out = run([sys.executable, "-c", snippet], installed).stdout.split()
    assert out[0] == out[1]  # the recorded fitness, reproduced exactly (repr of the same float)
    assert (elsewhere / "champion.gif").read_bytes()[:6] == b"GIF89a"


@pytest.mark.slow
@pytest.mark.subprocess
def test_the_tasks_walkthrough_evolves_a_task_of_ones_own_with_two_workers(installed):
    _, elsewhere, _ = installed
    script = code_block(ROOT / "docs" / "TASKS.md", "## Your own task")
    assert len(script.strip().splitlines()) < 30 and '"workers": 2' in script
    (elsewhere / "step_left.py").write_text(script)
    r = run([sys.executable, "step_left.py"], installed)
    assert "gen   10/10" in r.stdout
    rows = (elsewhere / "runs" / "step-left" / "generations.csv").read_text().splitlines()
    assert len(rows) == 11 and (elsewhere / "runs" / "step-left" / "champion.gif").is_file()
