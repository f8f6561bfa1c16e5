"""sgr as users install it: every package is in the distribution, and a plain (non-editable)
install runs `sgr evolve` from any folder, with the configs and world files it ships."""

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_every_package_is_listed_for_the_distribution():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts)
             for top in ("tsim", "tasks", "parity", "evolve", "sgr")
             for p in (ROOT / top).rglob("__init__.py")}
    assert found | {"evolve.configs"} == listed


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_plain_install_runs_sgr_evolve_from_another_folder(tmp_path):
    site = tmp_path / "site"
    build = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation",
                            "--target", str(site), str(ROOT)], capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    assert (site / "evolve" / "configs" / "sgr" / "quick.yaml").is_file()
    assert (site / "tasks" / "worlds" / "Walker-v0.json").is_file()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    run = subprocess.run([sys.executable, "-c", "import sys, evolve; print(evolve.__file__); "
                          "from evolve.cli import main; sys.exit(main(sys.argv[1:]))",
                          "evolve", "--generations", "1", "--pop", "8", "--out", "run", "--quiet"],
                         cwd=elsewhere, env={**os.environ, "PYTHONPATH": str(site)},
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith(str(site / "evolve")), run.stdout  # the installed copy ran
    assert (elsewhere / "run" / "generations.csv").read_text().count("\n") == 2
