"""The docs site (mkdocs.yml) builds in strict mode: a warning is an error, so a broken link, a
missing anchor, a page left out of the nav or an API name that does not resolve fails here; and the
API reference has a section for every public name of tsim, tasks, evolve and sgr.evogym."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
pytest.importorskip("mkdocs", reason="the docs extra: pip install -e '.[docs]'")
pytest.importorskip("mkdocstrings_handlers.python", reason="the docs extra: pip install -e '.[docs]'")
ENV = {"NO_MKDOCS_2_WARNING": "1", "PATH": "/usr/bin:/bin"}


def build(config: Path, site: Path) -> subprocess.CompletedProcess:
    # (not -q: it hides the warnings that --strict counts)
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config),
                           "-d", str(site)], cwd=config.parent, capture_output=True, text=True, timeout=600,
                          env=ENV)


@pytest.mark.slow
def test_the_docs_site_builds_strictly_with_every_public_name(tmp_path):
    import evolve
    import sgr.evogym
    import tasks
    import tsim

    r = build(ROOT / "mkdocs.yml", tmp_path / "site")
    assert r.returncode == 0, r.stdout + r.stderr
    for module in (tsim, tasks, evolve, sgr.evogym):
        html = (tmp_path / "site" / "reference" / "api" / module.__name__ / "index.html").read_text()
        missing = [n for n in module.__all__ if f'id="{module.__name__}.{n}"' not in html]
        assert not missing, f"{module.__name__}: no API section for {missing}"


@pytest.mark.slow
def test_a_broken_link_or_anchor_fails_the_strict_build(tmp_path):
    """A copy of the site whose pages name a source file that does not exist, and an anchor that
    does not exist: each fails the build, named."""
    for item in ("mkdocs.yml", "docs", "tools", "tsim", "tasks", "evolve", "sgr", "parity"):
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp_path / item)
    page = tmp_path / "docs" / "RUNS.md"
    page.write_text(page.read_text() + "\n[gone](../tsim/no_such_module.py)\n")
    r = build(tmp_path / "mkdocs.yml", tmp_path / "site")
    assert r.returncode != 0 and "no_such_module.py" in r.stdout + r.stderr
    page.write_text(page.read_text().replace("(../tsim/no_such_module.py)", "(EVOLVE.md#no-such-part)"))
    r = build(tmp_path / "mkdocs.yml", tmp_path / "site")
    assert r.returncode != 0 and "no-such-part" in r.stdout + r.stderr
